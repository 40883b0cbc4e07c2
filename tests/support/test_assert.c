/*
 * The assertions of sct_assert.h, in C: each passes when it holds, records
 * exactly one failure when it does not, and ASSERT_ stops the program.
 * The failures printed on the way are expected; the exit status says
 * whether every case came out as it should.
 *
 * Copyright (C) 2026 the shortcrust authors.
 * SPDX-License-Identifier: GPL-3.0-or-later
 */
#include "assert_cases.h"

int main(void) {
  int problems = run_cases();
  if (problems)
    fprintf(stderr, "%d case(s) wrong\n", problems);
  else
    printf("every case as expected (the failures above are deliberate)\n");
  return problems ? 1 : 0;
}
