/*
 * sliceclitest.h - what the slicecli suite's files share (check_slicecli.c,
 * check_slicecli_config.c): the shipped MK3S profile and models written as
 * STL for `stratum slice`.
 */
#ifndef STRATUM_TESTS_SLICECLITEST_H
#define STRATUM_TESTS_SLICECLITEST_H

#include "mesh.h"

#define MK3S "--printer prusa-i3-mk3s"

/* m as a binary STL scratch file named name; m is freed. */
const char *stl_file(struct mesh *m, const char *name);

#endif
