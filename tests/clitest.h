/*
 * clitest.h - what the cli suite's files share (check_cli.c,
 * check_cli_repair.c): models written as STL, `stratum check --json` run
 * and its report read.
 */
#ifndef STRATUM_TESTS_CLITEST_H
#define STRATUM_TESTS_CLITEST_H

#include <jansson.h>
#include <stdint.h>

#include "mesh.h"

/* Write m to a scratch file as binary STL and return its path. */
const char *write_mesh(struct mesh *m, const char *name);
/* Run `check --json` on path, expect the exit status, return the parsed report. */
json_t *check_json(const char *path, int want_status);
/* The integer field key of o (asserted present). */
json_int_t field(json_t *o, const char *key);
/* Whether the list (reasons, warnings) of o holds code. */
int has_reason(json_t *o, const char *list, const char *code);
/* An 84-byte binary STL header announcing n facets. */
void binary_header(unsigned char *buf, uint32_t n);

#endif
