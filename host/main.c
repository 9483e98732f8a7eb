/*
 * main.c - the `stratum` command line: dispatch to one subcommand.
 */
#include <stdio.h>
#include <string.h>

#include "commands.h"
#include "st_error.h"

static const struct cmd_entry commands[] = {
	{"check", cmd_check, "report a mesh's topology and whether it is printable"},
	{"repair", cmd_repair, "repair a mesh exactly into printable solids and write STL"},
	{"printers", cmd_printers, "list the printer profiles"},
	{"ports", cmd_ports, "list serial ports and the printers they match"},
	{"slice", cmd_slice, "slice a mesh into G-code for a printer"},
	{"print", cmd_print, "repair, slice and print a model in one go (simulated printer by default)"},
	{"send", cmd_send, "stream a G-code or X3G file to a printer (Marlin or Sailfish)"},
	{"console", cmd_console, "a terminal to a printer: G-code, replies, home, jog, preheat"},
	{"sim", cmd_sim, "run a simulated printer on a pseudo-terminal"},
	{"analyze", cmd_analyze, "measure the staircase error (cusp height) of printing a mesh in layers"},
	{"compare", cmd_compare, "the surface distance between two meshes, and chordal error against a finer one"},
	{"refine", cmd_refine, "split and move a coarse mesh's facets onto a finer one until within a tolerance"},
	{"preview", cmd_preview, "draw one layer of a G-code file as SVG or PNG"},
	{"x3g", cmd_x3g, "translate G-code to X3G for Sailfish printers, or list an X3G file"},
	{"jobs", cmd_jobs, "list the print jobs kept for --resume, show one, prune them"},
	{"serve", cmd_serve, "run the farm node: OctoPrint-compatible API and job queue"},
	{"farm", cmd_farm, "the farm view: every node's printers on one page, jobs to idle printers"},
};

#define NCOMMANDS (sizeof(commands) / sizeof(commands[0]))

int main(int argc, char **argv)
{
	if (argc < 2) {
		cmd_overview(commands, NCOMMANDS, stderr);
		return ST_EXIT_USAGE;
	}
	if (!strcmp(argv[1], "--help") || !strcmp(argv[1], "-h")) {
		cmd_overview(commands, NCOMMANDS, stdout);
		return ST_EXIT_OK;
	}
	if (!strcmp(argv[1], "help"))
		return cmd_help(commands, NCOMMANDS, argc - 1, argv + 1);
	if (!strcmp(argv[1], "--version")) {
		printf("stratum %s\n", STRATUM_VERSION);
		return ST_EXIT_OK;
	}
	for (size_t i = 0; i < NCOMMANDS; i++)
		if (!strcmp(argv[1], commands[i].name))
			return commands[i].run(argc - 1, argv + 1);
	fprintf(stderr, "stratum: unknown command '%s'\n", argv[1]);
	cmd_overview(commands, NCOMMANDS, stderr);
	return ST_EXIT_USAGE;
}
