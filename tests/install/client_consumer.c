/*
 * Built against the installed client library only (shortcrust-client.pc
 * or find_package(shortcrust)). Without arguments: the calls that need no
 * daemon, and a connection to a socket nobody listens on. With a socket
 * path: pings the daemon there and has it reconstruct a sampled sphere.
 *
 * SPDX-License-Identifier: GPL-3.0-or-later
 */
#define _POSIX_C_SOURCE 200809L
#include <shortcrust_client.h>

#include <math.h>
#include <stdio.h>
#include <string.h>
#include <time.h>

#define N 2000

static int fail(const char *what, const char *detail) {
  fprintf(stderr, "client_consumer: FAIL: %s%s%s\n", what,
          detail ? ": " : "", detail ? detail : "");
  return 1;
}

static int offline(void) {
  sc_client_params_t p;
  sc_client_params_init(&p);
  if (p.mode != SC_CLIENT_MODE_COCONE)
    return fail("default mode is not cocone", NULL);
  if (strcmp(sc_client_err_name(SC_CLIENT_ENODAEMON), "NODAEMON") != 0)
    return fail("error names", sc_client_err_name(SC_CLIENT_ENODAEMON));

  sc_client_options_t o;
  sc_client_options_init(&o);
  o.socket_path = "/nonexistent/shortcrust-install-test.sock";
  sc_client_t *c = NULL;
  char msg[256] = "";
  int rc = sc_client_connect(&o, &c, msg, sizeof msg);
  if (rc != SC_CLIENT_ENODAEMON || c != NULL)
    return fail("connecting to no daemon", sc_client_err_name(rc));
  printf("client_consumer: no daemon: %s (%s)\n", sc_client_strerror(rc), msg);
  return 0;
}

static int online(const char *sock) {
  sc_client_options_t o;
  sc_client_options_init(&o);
  o.socket_path = sock;
  sc_client_t *c = NULL;
  char msg[256] = "";
  int rc = SC_CLIENT_ENODAEMON;
  /* The daemon may still be starting (slowly under the sanitizers). */
  for (int i = 0; i < 300 && rc == SC_CLIENT_ENODAEMON; i++) {
    rc = sc_client_connect(&o, &c, msg, sizeof msg);
    if (rc == SC_CLIENT_ENODAEMON)
      nanosleep(&(struct timespec){0, 100 * 1000 * 1000}, NULL);
  }
  if (rc != 0)
    return fail("connect", msg);

  int bad = 0;
  double rtt = 0;
  if ((rc = sc_client_ping(c, 10000, &rtt)) != 0)
    bad = fail("ping", sc_client_last_error(c));

  static double xyz[3 * N];
  const double golden = 3.0 - sqrt(5.0), pi = 3.14159265358979323846;
  for (int i = 0; i < N; i++) {
    double z = 1.0 - (2.0 * i + 1.0) / N, r = sqrt(1.0 - z * z);
    xyz[3 * i] = r * cos(pi * golden * i);
    xyz[3 * i + 1] = r * sin(pi * golden * i);
    xyz[3 * i + 2] = z;
  }
  sc_client_params_t p;
  sc_client_params_init(&p);
  sc_client_job_t *job = NULL;
  if (!bad && (rc = sc_client_submit(c, &p, xyz, N, &job)) != 0)
    bad = fail("submit", sc_client_last_error(c));
  if (!bad && (rc = sc_client_wait(c, job, 30000)) != 0)
    bad = fail("job", sc_client_job_message(job));
  if (!bad) {
    sc_client_mesh_t m;
    sc_client_job_mesh(job, &m);
    printf("client_consumer: ping %.3f ms, %llu triangles from the daemon\n",
           rtt * 1e3, (unsigned long long)m.triangle_count);
    if (m.triangle_count != 2 * N - 4 || m.component_count != 1 ||
        m.genus[0] != 0)
      bad = fail("the sphere did not come back closed", NULL);
  }
  sc_client_job_free(job);
  sc_client_free(c);
  return bad;
}

int main(int argc, char **argv) {
  if (offline())
    return 1;
  return argc > 1 ? online(argv[1]) : 0;
}
