/*
 * sfcheck.h - test helpers shared by the suites that print to the
 * simulated Sailfish printer (check_send.c, check_serve.c): the reference
 * commands of a G-code file (`stratum x3g`, decoded) and the comparison of
 * the simulator's execution log with them.
 */
#ifndef STRATUM_TESTS_SFCHECK_H
#define STRATUM_TESTS_SFCHECK_H

#include <jansson.h>
#include <stdbool.h>
#include <stdio.h>

#define SFC_PRINTER "flashforge-creator-pro"

/*
 * sfc_reference - `stratum x3g gcode -o x3g --printer SFC_PRINTER`, decoded
 * into dec: the commands as a JSON array (caller decrefs); at least min.
 */
json_t *sfc_reference(const char *gcode, const char *x3g, const char *dec, size_t min);

/*
 * sfc_check_log - the next json_array_size(cmds) lines of the simulator's
 * log f hold the commands of cmds, in order, numbered from 1: the same
 * codes and, with fields, the step positions and DDA rate of every move and
 * the value of every tool action.  Fails the test otherwise.
 */
void sfc_check_log(FILE *f, json_t *cmds, bool fields);

#endif /* STRATUM_TESTS_SFCHECK_H */
