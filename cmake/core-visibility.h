/*
 * Included before every source of the core (-include, see
 * cmake/ShortcrustPackage.cmake). The core is built -fvisibility=hidden, so
 * that the shared library exports nothing but its C API; declaring the
 * public header here, once, under default visibility marks exactly the
 * functions it declares as the exported ones, without an export macro in
 * the header itself. The include guard makes the sources' own
 * #include "shortcrust.h" a no-op.
 *
 * SPDX-License-Identifier: GPL-3.0-or-later
 */
#pragma GCC visibility push(default)
#include "shortcrust.h"
#pragma GCC visibility pop
