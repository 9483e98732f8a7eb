/*
 * sfcheck.h - test helpers shared by the suites that print to the
 * simulated Sailfish printer (check_send.c, check_serve.c, check_print.c): the reference
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

/*
 * sfc_check_resumed - the simulator log of a resumed print holds a
 * preamble (bed and nozzle waits, X/Y homed to their endstops and never Z,
 * a set position before the homing, the calibrated X/Y home offsets
 * recalled) and then exactly the commands of gcode from file line from on,
 * as one translation of the whole file gives them (X, Y, Z steps exact,
 * extruders within a step; a first move to where the preamble left the
 * nozzle may be missing: it has no length).  Returns the Z (mm) the set position gave.
 */
double sfc_check_resumed(const char *gcode, uint64_t from, const char *log);

#endif /* STRATUM_TESTS_SFCHECK_H */
