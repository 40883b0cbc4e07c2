/*
 * The listening sockets: the Unix socket, taken from systemd (LISTEN_FDS)
 * or bound at --socket with its mode, replacing a stale socket file and
 * refusing to start when another daemon is alive on the path; and the TCP
 * listeners of --listen, whose clients must send the token (auth.c).
 *
 * Two daemons started at once must not both decide that the file is stale
 * and unlink each other's sockets, so the check and the bind happen while
 * holding an flock() on PATH.lock, kept for the daemon's whole life.
 *
 * Copyright (C) 2026 the shortcrust authors.
 * SPDX-License-Identifier: GPL-3.0-or-later
 */
#include "daemon.h"
#include "log.h"

#include <arpa/inet.h>
#include <errno.h>
#include <fcntl.h>
#include <netdb.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>
#include <sys/file.h>
#include <sys/socket.h>
#include <sys/stat.h>
#include <sys/un.h>
#include <unistd.h>

/* systemd passes sockets from fd 3 on (sd_listen_fds(3)). */
#define SCD_LISTEN_FDS_START 3

static ino_t socket_ino;

/* Returns the fd systemd passed, -1 when none was passed, -2 on error. */
static int systemd_socket(void) {
  const char *pid_s = getenv("LISTEN_PID");
  const char *fds_s = getenv("LISTEN_FDS");
  if (!pid_s || !fds_s)
    return -1;
  char *end;
  errno = 0;
  long long pid = strtoll(pid_s, &end, 10);
  if (errno || *end || pid != (long long)getpid())
    return -1;
  long long n = strtoll(fds_s, &end, 10);
  int bad = errno || *end;
  /* Children must not think the sockets are theirs. */
  unsetenv("LISTEN_PID");
  unsetenv("LISTEN_FDS");
  unsetenv("LISTEN_FDNAMES");
  if (bad || n < 1)
    return -1;
  if (n > 1)
    scd_warn("systemd passed %lld sockets; using the first one only", n);
  int fd = SCD_LISTEN_FDS_START;
  int type = 0, listening = 0;
  socklen_t len = sizeof type;
  struct sockaddr_un sa;
  socklen_t salen = sizeof sa;
  if (getsockopt(fd, SOL_SOCKET, SO_TYPE, &type, &len) != 0 ||
      type != SOCK_STREAM) {
    scd_error("socket activation: fd %d is not a stream socket", fd);
    return -2;
  }
  len = sizeof listening;
  if (getsockopt(fd, SOL_SOCKET, SO_ACCEPTCONN, &listening, &len) != 0 ||
      !listening) {
    scd_error("socket activation: fd %d is not listening", fd);
    return -2;
  }
  if (getsockname(fd, (struct sockaddr *)&sa, &salen) != 0 ||
      sa.sun_family != AF_UNIX) {
    scd_error("socket activation: fd %d is not a Unix domain socket", fd);
    return -2;
  }
  fcntl(fd, F_SETFD, FD_CLOEXEC);
  return fd;
}

/* Takes PATH.lock; -1 (logged) when another daemon holds it. */
static int take_lock(scd_server_t *srv) {
  int n = snprintf(srv->lock_path, sizeof srv->lock_path, "%s.lock",
                   srv->socket_path);
  if (n < 0 || (size_t)n >= sizeof srv->lock_path) {
    scd_error("socket path too long: %s", srv->socket_path);
    return -1;
  }
  /* A daemon leaving unlinks the lock file; if we locked the file it just
   * unlinked, the lock protects nothing, so check and try again. */
  for (int attempt = 0; attempt < 10; attempt++) {
    int fd = open(srv->lock_path, O_RDWR | O_CREAT | O_CLOEXEC, 0600);
    if (fd < 0 && errno == ENOENT) {
      scd_error("the directory of %s does not exist; create it, or choose "
                "another path with --socket",
                srv->socket_path);
      return -1;
    }
    if (fd < 0) {
      scd_error("cannot open %s: %s", srv->lock_path, strerror(errno));
      return -1;
    }
    if (flock(fd, LOCK_EX | LOCK_NB) != 0) {
      int e = errno;
      close(fd);
      if (e == EWOULDBLOCK)
        scd_error("another shortcrustd is running on %s (it holds %s); "
                  "refusing to start",
                  srv->socket_path, srv->lock_path);
      else
        scd_error("cannot lock %s: %s", srv->lock_path, strerror(e));
      return -1;
    }
    struct stat a, b;
    if (fstat(fd, &a) == 0 && stat(srv->lock_path, &b) == 0 &&
        a.st_dev == b.st_dev && a.st_ino == b.st_ino) {
      srv->lock_fd = fd;
      return 0;
    }
    close(fd);
  }
  scd_error("cannot take %s: it keeps being replaced", srv->lock_path);
  return -1;
}

/* Deals with whatever is at the path already: 0 when the path is free. */
static int clear_path(const char *path, const struct sockaddr_un *sa) {
  struct stat st;
  if (lstat(path, &st) != 0) {
    if (errno == ENOENT)
      return 0;
    scd_error("cannot inspect %s: %s", path, strerror(errno));
    return -1;
  }
  if (!S_ISSOCK(st.st_mode)) {
    scd_error("%s exists and is not a socket; refusing to replace it", path);
    return -1;
  }
  int fd = socket(AF_UNIX, SOCK_STREAM | SOCK_CLOEXEC, 0);
  if (fd < 0) {
    scd_error("socket: %s", strerror(errno));
    return -1;
  }
  int rc = connect(fd, (const struct sockaddr *)sa, sizeof *sa);
  int e = errno;
  close(fd);
  if (rc == 0) {
    scd_error("another daemon is listening on %s; refusing to start", path);
    return -1;
  }
  if (e != ECONNREFUSED && e != ENOENT) {
    scd_error("cannot probe %s: %s", path, strerror(e));
    return -1;
  }
  scd_warn("removing stale socket %s left by a daemon that is gone", path);
  if (unlink(path) != 0 && errno != ENOENT) {
    scd_error("cannot remove %s: %s", path, strerror(errno));
    return -1;
  }
  return 0;
}

static int bind_socket(scd_server_t *srv) {
  const char *path = srv->socket_path;
  struct sockaddr_un sa;
  memset(&sa, 0, sizeof sa);
  sa.sun_family = AF_UNIX;
  if (strlen(path) >= sizeof sa.sun_path) {
    scd_error("socket path too long (at most %zu bytes): %s",
              sizeof sa.sun_path - 1, path);
    return -1;
  }
  memcpy(sa.sun_path, path, strlen(path) + 1);
  if (take_lock(srv) != 0)
    return -1;
  if (clear_path(path, &sa) != 0)
    return -1;
  int fd = socket(AF_UNIX, SOCK_STREAM | SOCK_CLOEXEC, 0);
  if (fd < 0) {
    scd_error("socket: %s", strerror(errno));
    return -1;
  }
  /* The umask makes the socket appear with its final mode, so there is no
   * moment at which others may connect; chmod() then sets it exactly. */
  mode_t old = umask(~srv->cfg.socket_mode & 0777);
  int rc = bind(fd, (struct sockaddr *)&sa, sizeof sa);
  int e = errno;
  umask(old);
  if (rc != 0) {
    scd_error("cannot bind %s: %s", path, strerror(e));
    close(fd);
    return -1;
  }
  srv->unlink_at_exit = 1;
  struct stat st;
  if (chmod(path, srv->cfg.socket_mode) != 0 || lstat(path, &st) != 0) {
    scd_error("cannot set the mode of %s: %s", path, strerror(errno));
    close(fd);
    return -1;
  }
  socket_ino = st.st_ino;
  if (listen(fd, SOMAXCONN) != 0) {
    scd_error("cannot listen on %s: %s", path, strerror(errno));
    close(fd);
    return -1;
  }
  return fd;
}

int scd_listen_open(scd_server_t *srv) {
  int fd = systemd_socket();
  if (fd == -2)
    return -1;
  if (fd >= 0) {
    struct sockaddr_un sa;
    socklen_t len = sizeof sa;
    memset(&sa, 0, sizeof sa);
    getsockname(fd, (struct sockaddr *)&sa, &len);
    snprintf(srv->socket_path, sizeof srv->socket_path, "%s",
             sa.sun_path[0] ? sa.sun_path : "(abstract)");
    scd_info("using the socket systemd passed: %s", srv->socket_path);
  } else {
    snprintf(srv->socket_path, sizeof srv->socket_path, "%s",
             srv->cfg.socket_path);
    if (strlen(srv->cfg.socket_path) >= sizeof srv->socket_path) {
      scd_error("socket path too long: %s", srv->cfg.socket_path);
      return -1;
    }
    fd = bind_socket(srv);
    if (fd < 0)
      return -1;
  }
  int rc = uv_pipe_init(srv->loop, &srv->listener, 0);
  if (rc == 0)
    rc = uv_pipe_open(&srv->listener, fd);
  if (rc != 0) {
    scd_error("cannot use the listening socket: %s", uv_strerror(rc));
    close(fd);
    return -1;
  }
  srv->listener_open = 1;
  srv->listener.data = srv;
  return 0;
}

static void on_tcp_connection(uv_stream_t *listener, int status) {
  scd_tcp_listener_t *l = listener->data;
  if (status < 0) {
    scd_warn("accept on %s: %s", l->name, uv_strerror(status));
    return;
  }
  scd_conn_accept(l->srv, listener, 1);
}

/* Resolves, binds and listens on one tcp:// address. */
static int bind_tcp(scd_server_t *srv, scd_tcp_listener_t *l,
                    const char *text) {
  scp_address_t a;
  if (scp_address_parse(text, &a) != 0 || a.kind != SCP_ADDR_TCP) {
    scd_error("--listen %s: want tcp://HOST:PORT", text);
    return -1;
  }
  char port[8];
  snprintf(port, sizeof port, "%u", (unsigned)a.port);
  struct addrinfo hints, *res = NULL;
  memset(&hints, 0, sizeof hints);
  hints.ai_family = AF_UNSPEC;
  hints.ai_socktype = SOCK_STREAM;
  hints.ai_flags = AI_PASSIVE | AI_NUMERICSERV;
  int rc = getaddrinfo(a.host, port, &hints, &res);
  if (rc != 0 || !res) {
    scd_error("--listen %s: cannot resolve %s: %s", text, a.host,
              gai_strerror(rc));
    return -1;
  }
  uv_tcp_init(srv->loop, &l->tcp);
  l->tcp.data = l;
  l->srv = srv;
  l->open = 1;
  srv->ntcp++;
  /* The first address the name gives; a name with several is better
   * given as the literal wanted. */
  int urc = uv_tcp_bind(&l->tcp, res->ai_addr, 0);
  freeaddrinfo(res);
  if (urc == 0)
    urc = uv_listen((uv_stream_t *)&l->tcp, SOMAXCONN, on_tcp_connection);
  if (urc != 0) {
    scd_error("cannot listen on %s: %s", text, uv_strerror(urc));
    return -1;
  }
  /* With port 0 the system chose one: name the listener by it. */
  struct sockaddr_storage ss;
  int len = sizeof ss;
  if (uv_tcp_getsockname(&l->tcp, (struct sockaddr *)&ss, &len) == 0)
    a.port =
        ntohs(ss.ss_family == AF_INET6 ? ((struct sockaddr_in6 *)&ss)->sin6_port
                                       : ((struct sockaddr_in *)&ss)->sin_port);
  scp_address_format(&a, l->name, sizeof l->name);
  return 0;
}

int scd_listen_tcp(scd_server_t *srv) {
  for (unsigned i = 0; i < srv->cfg.nlisten; i++)
    if (bind_tcp(srv, &srv->tcp[i], srv->cfg.listen[i]) != 0)
      return -1;
  return 0;
}

void scd_listen_close(scd_server_t *srv) {
  if (srv->listener_open) {
    uv_close((uv_handle_t *)&srv->listener, NULL);
    srv->listener_open = 0;
  }
  for (unsigned i = 0; i < srv->ntcp; i++)
    if (srv->tcp[i].open) {
      uv_close((uv_handle_t *)&srv->tcp[i].tcp, NULL);
      srv->tcp[i].open = 0;
    }
}

void scd_listen_cleanup(scd_server_t *srv) {
  if (srv->unlink_at_exit) {
    struct stat st;
    /* Only our own socket: never one that replaced it. */
    if (lstat(srv->socket_path, &st) == 0 && st.st_ino == socket_ino)
      unlink(srv->socket_path);
    srv->unlink_at_exit = 0;
  }
  if (srv->lock_fd >= 0) {
    unlink(srv->lock_path);
    close(srv->lock_fd);
    srv->lock_fd = -1;
  }
}
