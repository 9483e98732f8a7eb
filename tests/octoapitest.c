/*
 * octoapitest.c - the helpers of octoapitest.h.
 */
#include <check.h>
#include <stdio.h>
#include <string.h>

#include "octoapitest.h"
#include "servetest.h"

const char oa_estimated[] =
	"M73 P0 R10\nG4 S1\nM73 P50 R5\nG4 S%d\nM73 P100 R0\n"
	"; filament used [mm] = 812.5\n; filament used [cm3] = 1.95\n"
	"; estimated printing time (normal mode) = 10m 2s\n";

void oa_start(struct node_proc *np, const char *printers)
{
	sv_write_config(np, printers, 8);
	sv_start(np);
}

void oa_store(int port, const char *folder, const char *name, const char *text)
{
	struct resp r;

	sv_upload(port, "", KEY_UP, name, strlen(name), folder, strlen(folder), "false", text,
		  strlen(text), NULL, true, &r);
	ck_assert_msg(r.status == 201, "%d %s", r.status, r.body);
	sv_resp_free(&r);
}

char *oa_dwell(int secs)
{
	static char text[512];

	snprintf(text, sizeof(text), oa_estimated, secs);
	return text;
}
