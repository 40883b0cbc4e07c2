/*
 * Included before every source of the client library (-include, see
 * cmake/ShortcrustPackage.cmake): as core-visibility.h does for the core,
 * gives the declarations of the public header default visibility while the
 * library, the protocol codec and the file module inside it are built
 * -fvisibility=hidden.
 *
 * SPDX-License-Identifier: GPL-3.0-or-later
 */
#pragma GCC visibility push(default)
#include "shortcrust_client.h"
#pragma GCC visibility pop
