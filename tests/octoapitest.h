/*
 * octoapitest.h - what the octoapi suite's call tests share (check_octoapi.c,
 * check_octoapi_printer.c): the keys' headers, a node with given printers,
 * G-code stored without printing, a job that dwells.
 */
#ifndef STRATUM_TESTS_OCTOAPITEST_H
#define STRATUM_TESTS_OCTOAPITEST_H

#include "servetest.h"

#define CTL "X-Api-Key: " KEY_CTL
#define UP "X-Api-Key: " KEY_UP
#define RO "X-Api-Key: " KEY_READ

/* A test-instant Prusa and a test-instant Creator Pro (two extruders). */
#define MK3S_AND_CREATOR                                                             \
	"[printer mk3s]\nprofile = prusa-i3-mk3s\nport = test-instant\n\n"          \
	"[printer cp]\nprofile = flashforge-creator-pro\nport = test-instant\n"

/* G-code that says its estimate and filament as PrusaSlicer writes them,
 * with M73 marks, and dwells %d seconds (oa_dwell fills it in). */
extern const char oa_estimated[];

/* The node np with the [printer] sections printers, started. */
void oa_start(struct node_proc *np, const char *printers);
/* Store a G-code text in folder (may be "") of mk3s without printing it. */
void oa_store(int port, const char *folder, const char *name, const char *text);
/* A G-code text that dwells secs seconds (a job held printing); a static
 * buffer, overwritten by the next call. */
char *oa_dwell(int secs);

#endif
