/*
 * check_help.c - every option a command's parser takes is in its --help,
 * its man page and the shell completion (host/cmd_help.c): the tables are
 * listed by `stratum help --options CMD`, and each option is fed back to
 * the parser, which must take it (not "unknown option").  Also `stratum
 * help CMD`, the man pages through groff's checks and the completion
 * scripts run by bash and zsh.
 */
#include <check.h>
#include <stdbool.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>

#include "suites.h"
#include "testutil.h"

static char out[1 << 18];
static char help[1 << 16], man[1 << 16], comp[1 << 17];

/* Whether text holds name as a whole option (not the start of a longer one). */
static bool has_option(const char *text, const char *name)
{
	size_t n = strlen(name);

	for (const char *p = strstr(text, name); p; p = strstr(p + 1, name)) {
		char after = p[n];

		if (!(after >= 'a' && after <= 'z') && after != '-' && after != '_')
			return true;
	}
	return false;
}

/* name as man(7) writes it: every '-' as "\-". */
static void roff_name(char *buf, size_t cap, const char *name)
{
	size_t o = 0;

	for (; *name && o + 3 < cap; name++) {
		if (*name == '-')
			buf[o++] = '\\';
		buf[o++] = *name;
	}
	buf[o] = '\0';
}

/* The branch "\tCMD)\n ... ;;" of the bash completion script in comp, cut out. */
static char *bash_branch(char *script, const char *cmd)
{
	char head[64], *b, *end;

	snprintf(head, sizeof(head), "\n\t%s)\n", cmd);
	b = strstr(script, head);
	ck_assert_msg(b != NULL, "the bash completion has no branch for %s", cmd);
	end = strstr(b, ";;");
	ck_assert(end != NULL);
	*end = '\0';
	return b;
}

START_TEST(every_option_in_help_man_completion_and_parser)
{
	char commands[1024], *save = NULL, *cmd;
	static char bashc[1 << 17];
	size_t checked = 0;

	ck_assert_int_eq(tu_run(commands, sizeof(commands), "help --commands"), 0);
	ck_assert_int_eq(tu_run(bashc, sizeof(bashc), "help --completion bash"), 0);
	ck_assert_int_eq(tu_run(comp, sizeof(comp), "help --completion zsh"), 0);
	for (cmd = strtok_r(commands, "\n", &save); cmd; cmd = strtok_r(NULL, "\n", &save)) {
		char table[8192], *line, *lsave = NULL;
		static char branch_copy[1 << 17];
		char *branch;

		ck_assert_int_eq(tu_run(table, sizeof(table), "help --options %s", cmd), 0);
		ck_assert_int_eq(tu_run(help, sizeof(help), "%s --help", cmd), 0);
		ck_assert_int_eq(tu_run(man, sizeof(man), "help --man %s", cmd), 0);
		memcpy(branch_copy, bashc, sizeof(branch_copy));
		branch = bash_branch(branch_copy, cmd);
		for (line = strtok_r(table, "\n", &lsave); line; line = strtok_r(NULL, "\n", &lsave)) {
			char name[80], letter[8], kind[16], has[16], rname[200];
			int rc;

			ck_assert_msg(sscanf(line, "%79s %7s %15s %15s", name, letter, kind, has) == 4,
				      "%s: bad table line '%s'", cmd, line);
			ck_assert_msg(!strcmp(has, "help"), "stratum %s %s has no help text", cmd,
				      name);
			ck_assert_msg(has_option(help, name), "stratum %s --help does not list %s",
				      cmd, name);
			roff_name(rname, sizeof(rname), name);
			ck_assert_msg(has_option(man, rname), "stratum-%s(1) does not list %s", cmd,
				      name);
			ck_assert_msg(has_option(branch, name),
				      "the bash completion of %s does not offer %s", cmd, name);
			ck_assert_msg(has_option(comp, name), "the zsh completion does not offer %s",
				      name);
			/* The parser takes it: a flag (or an optional value) then --help
			 * prints the usage; a value option without its value asks for it. */
			if (strcmp(kind, "value")) {
				rc = tu_run(out, sizeof(out), "%s %s --help", cmd, name);
				ck_assert_msg(rc == 0 && !strncmp(out, "usage:", 6),
					      "stratum %s %s --help: exit %d: %.300s", cmd, name, rc,
					      out);
			} else {
				const char *forms[] = {name, letter[1] ? letter : NULL};

				for (int f = 0; f < 2 && forms[f]; f++) {
					rc = tu_run(out, sizeof(out), "%s %s", cmd, forms[f]);
					ck_assert_msg(rc == 2 && !strstr(out, "unknown option") &&
							  strstr(out, forms[f]),
						      "stratum %s %s (no value): exit %d: %.300s", cmd,
						      forms[f], rc, out);
				}
			}
			checked++;
		}
	}
	ck_assert_msg(checked > 80, "only %zu options listed", checked);
}
END_TEST

/* `stratum help CMD` is CMD's --help; an unknown option is named as one. */
START_TEST(help_command_and_unknown_option)
{
	char want[1 << 16];

	ck_assert_int_eq(tu_run(out, sizeof(out), "help print"), 0);
	ck_assert_int_eq(tu_run(want, sizeof(want), "print --help"), 0);
	ck_assert_str_eq(out, want);
	ck_assert_msg(!strncmp(out, "usage: stratum print ", 21), "%.200s", out);
	ck_assert_int_eq(tu_run(out, sizeof(out), "help no-such"), 2);
	ck_assert_msg(strstr(out, "no command 'no-such'"), "%s", out);
	ck_assert_int_eq(tu_run(out, sizeof(out), "sim --bogus"), 2);
	ck_assert_msg(strstr(out, "stratum sim: unknown option '--bogus'"), "%.300s", out);
	ck_assert_msg(!strstr(out, "missing"), "%.300s", out);
	ck_assert_int_eq(tu_run(out, sizeof(out), "slice --help"), 0);
	ck_assert_msg(!strstr(out, "not in yet") && !strstr(out, "not yet"), "%s", out);
	ck_assert_int_eq(tu_run(out, sizeof(out), "slice --help=pdf"), 2);
}
END_TEST

/* groff checks every man page (-ww: all warnings) when it is installed. */
START_TEST(man_pages_pass_groff)
{
	char commands[1024], *save = NULL, *cmd;

	if (tu_sh(out, sizeof(out), "command -v groff") != 0) {
		fprintf(stderr, "help: groff is not installed; man pages not checked by groff\n");
		return;
	}
	ck_assert_int_eq(tu_run(commands, sizeof(commands), "help --commands"), 0);
	ck_assert_int_eq(tu_sh(out, sizeof(out), "%s help --man | groff -man -ww -z", tu_bin()),
			 0);
	ck_assert_msg(!*out, "stratum(1): %s", out);
	for (cmd = strtok_r(commands, "\n", &save); cmd; cmd = strtok_r(NULL, "\n", &save)) {
		ck_assert_int_eq(tu_sh(out, sizeof(out),
				       "%s help --man %s | groff -man -ww -z", tu_bin(), cmd), 0);
		ck_assert_msg(!*out, "stratum-%s(1): %s", cmd, out);
	}
}
END_TEST

/* The bash script completes commands, options, printer names and files;
 * zsh reads its script without a syntax error (when zsh is installed). */
START_TEST(completion_scripts_run)
{
	const char *script = tu_path("stratum.bash"), *zscript = tu_path("_stratum");

	ck_assert_int_eq(tu_sh(out, sizeof(out), "%s help --completion bash > '%s'", tu_bin(),
			       script), 0);
	ck_assert_int_eq(
	    tu_sh(out, sizeof(out),
		  "bash -c '. \"%s\"; c() { COMP_WORDS=(\"$@\"); COMP_CWORD=$(($# - 1)); "
		  "_stratum; echo \"[${COMPREPLY[*]}]\"; }; "
		  "c %s sl; c %s slice --layer-h; c %s slice --printer prusa-i3; "
		  "c %s sim --no-f; c %s slice --fill-dens; c %s help pri; "
		  "c %s check docs/examples/brack'",
		  script, tu_bin(), tu_bin(), tu_bin(), tu_bin(), tu_bin(), tu_bin(), tu_bin()),
	    0);
	ck_assert_msg(strstr(out, "[slice]\n"), "%s", out);
	ck_assert_msg(strstr(out, "--layer-height"), "%s", out);
	ck_assert_msg(strstr(out, "[prusa-i3-mk3s]\n"), "%s", out);
	ck_assert_msg(strstr(out, "[--no-firmware-name]\n"), "%s", out);
	ck_assert_msg(strstr(out, "[--fill-density]\n"), "%s", out);
	ck_assert_msg(strstr(out, "[printers print]\n"), "%s", out);
	ck_assert_msg(strstr(out, "[docs/examples/bracket.stl]\n"), "%s", out);
	ck_assert_int_eq(tu_sh(out, sizeof(out), "%s help --completion zsh > '%s'", tu_bin(),
			       zscript), 0);
	if (tu_sh(out, sizeof(out), "command -v zsh") != 0) {
		fprintf(stderr, "help: zsh is not installed; its completion is not checked\n");
		return;
	}
	ck_assert_msg(tu_sh(out, sizeof(out), "zsh -n '%s'", zscript) == 0, "%s", out);
}
END_TEST

Suite *help_suite(void)
{
	Suite *s = suite_create("help");
	TCase *tc = tcase_create("help");

	tcase_set_timeout(tc, 300);
	tcase_add_test(tc, every_option_in_help_man_completion_and_parser);
	tcase_add_test(tc, help_command_and_unknown_option);
	tcase_add_test(tc, man_pages_pass_groff);
	tcase_add_test(tc, completion_scripts_run);
	suite_add_tcase(s, tc);
	return s;
}
