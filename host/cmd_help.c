/*
 * cmd_help.c - `stratum help`, and every other form of a command's option
 * table (commands.h): man pages, bash and zsh completion, and the plain
 * option list tests/check_help.c feeds back to the parser.  The Makefile
 * runs `stratum help --man` and `--completion` at build time, so the man
 * pages and the completion are the tables cmd_parse reads and --help prints.
 */
#include <ctype.h>
#include <stdbool.h>
#include <stdio.h>
#include <string.h>

#include "cfgopt.h"
#include "commands.h"

#define HELP_CMD "stratum help"

void cmd_overview(const struct cmd_entry *cmds, size_t n, FILE *f)
{
	fprintf(f, "usage: stratum <command> [options]\n\ncommands:\n");
	for (size_t i = 0; i < n; i++)
		fprintf(f, "  %-10s %s\n", cmds[i].name, cmds[i].summary);
	fprintf(f, "\n'stratum help <command>' or 'stratum <command> --help' describes a "
		   "command's options;\n'man stratum-<command>' once installed (make install).\n");
}

/* ---------------------------------------------------------------------------
 * roff (man(7))
 */

/* s[0..len) as roff text: backslashes and '-' escaped, a '.' or '\'' that
 * would start a line made literal. */
static void roff_put(FILE *f, const char *s, size_t len, bool at_line_start)
{
	for (size_t i = 0; i < len; i++) {
		char c = s[i];

		if (at_line_start && (c == '.' || c == '\''))
			fputs("\\&", f);
		if (c == '\\')
			fputs("\\e", f);
		else if (c == '-')
			fputs("\\-", f);
		else
			fputc(c, f);
		at_line_start = c == '\n';
	}
}

static void roff_str(FILE *f, const char *s)
{
	roff_put(f, s, strlen(s), true);
}

/* The option's label: \fB-o\fR, \fB--output\fR \fIOUT\fR. */
static void roff_label(FILE *f, const struct cmd_opt *o)
{
	fputs(".TP\n", f);
	if (o->letter)
		fprintf(f, "\\fB\\-%c\\fR, ", o->letter);
	fputs("\\fB", f);
	roff_put(f, o->name, strlen(o->name), false);
	fputs("\\fR", f);
	if (o->arg) {
		fputs(" \\fI", f);
		roff_put(f, o->arg, strlen(o->arg), false);
		fputs("\\fR", f);
	}
	fputc('\n', f);
}

/* One option: its label, then its help as one filled paragraph. */
static void roff_opt(FILE *f, const struct cmd_opt *o)
{
	char text[CMD_HELP_MAX];

	roff_label(f, o);
	cmd_opt_help(o, text, sizeof(text));
	for (char *t = text; *t; t++)
		if (*t == '\n')
			*t = ' ';
	roff_str(f, text);
	fputc('\n', f);
}

/* Paragraphs of text (blank lines between): filled, or kept line by line
 * when one of their lines is indented (lists, examples). */
static void roff_paragraphs(FILE *f, const char *s)
{
	while (*s) {
		const char *end, *p;
		size_t len;
		bool indented;

		while (*s == '\n')
			s++;
		if (!*s)
			break;
		indented = s[0] == ' ';
		end = strstr(s, "\n\n");
		len = end ? (size_t)(end - s) + 1 : strlen(s);
		for (p = s; p < s + len && !indented; p++)
			indented = p[0] == '\n' && p[1] == ' ';
		fputs(indented ? ".PP\n.nf\n" : ".PP\n", f);
		roff_put(f, s, len, true);
		if (s[len - 1] != '\n')
			fputc('\n', f);
		if (indented)
			fputs(".fi\n", f);
		s += len;
	}
}

/* The command's name after "stratum ": "slice". */
static const char *short_name(const struct cmd_spec *spec)
{
	const char *sp = strrchr(spec->cmd, ' ');

	return sp ? sp + 1 : spec->cmd;
}

/*
 * The body of stratum-CMD(1) after its NAME (cmd_help prints the .TH and
 * NAME, which need the summary): the head's usage lines as SYNOPSIS, the
 * rest of it as DESCRIPTION, the table as OPTIONS, the settings options,
 * the tail.
 */
static void man_body(const struct cmd_spec *spec, FILE *f)
{
	const char *s = spec->head, *nl;
	size_t no;
	const struct cmd_opt *cfg = cfgopt_options(&no);
	static const struct cmd_opt help = {"--help", 'h', CMD_FLAG, NULL, 0, 0, 0, NULL, NULL,
					    "print the help and exit", NULL, NULL};

	fputs(".SH SYNOPSIS\n.nf\n", f);
	/* "usage: " and the lines that continue it, indented under it */
	while (*s && (!strncmp(s, "usage: ", 7) || s[0] == ' ')) {
		nl = strchr(s, '\n');
		size_t len = nl ? (size_t)(nl - s) : strlen(s), skip = 0;

		if (!strncmp(s, "usage: ", 7))
			skip = 7;
		while (skip < 7 && skip < len && s[skip] == ' ')
			skip++;
		roff_put(f, s + skip, len - skip, true);
		fputc('\n', f);
		s += len + (nl ? 1 : 0);
	}
	fputs(".fi\n.SH DESCRIPTION\n", f);
	roff_paragraphs(f, s);
	fputs(".SH OPTIONS\n", f);
	for (size_t k = 0; k < spec->nopt; k++)
		roff_opt(f, &spec->opt[k]);
	roff_opt(f, &help);
	if (spec->cfg) {
		fputs(".SH SETTINGS OPTIONS\n", f);
		if (spec->mid)
			roff_paragraphs(f, spec->mid);
		for (size_t k = 0; k < no; k++)
			roff_opt(f, &cfg[k]);
		roff_paragraphs(f, cfgopt_usage_tail());
	} else if (spec->mid) {
		roff_paragraphs(f, spec->mid);
	}
	if (spec->tail) {
		fputs(strstr(spec->tail, "Exit status") ? ".SH EXIT STATUS\n" : ".SH NOTES\n", f);
		roff_paragraphs(f, spec->tail);
	}
	fputs(".SH SEE ALSO\n\\fBstratum\\fR(1); the guides in share/doc/stratum of the "
	      "install prefix (docs/ of the source tree).\n", f);
}

/* ---------------------------------------------------------------------------
 * Shell completion: each command's branch; cmd_help writes the frame.
 */

/* s in single quotes for the shell. */
static void sh_quote(FILE *f, const char *s)
{
	fputc('\'', f);
	for (; *s; s++)
		if (*s == '\'')
			fputs("'\\''", f);
		else
			fputc(*s, f);
	fputc('\'', f);
}

/* bash: the names of spec's options (with values_only, those that take a
 * value), and with the settings options the names of those. */
static void bash_names(FILE *f, const struct cmd_spec *spec, bool values_only)
{
	size_t no;
	const struct cmd_opt *cfg = cfgopt_options(&no);

	for (size_t k = 0; k < spec->nopt; k++) {
		if (values_only && spec->opt[k].kind == CMD_FLAG)
			continue;
		if (spec->opt[k].letter)
			fprintf(f, " -%c", spec->opt[k].letter);
		fprintf(f, " %s", spec->opt[k].name);
	}
	for (size_t k = 0; spec->cfg && k + 1 < no; k++) /* the last is --KEY-NAME */
		fprintf(f, " %s", cfg[k].name);
}

/* bash: opts (every option) and vals (those that take a value). */
static void bash_branch(const struct cmd_spec *spec, FILE *f)
{
	fprintf(f, "\t%s)\n\t\topts=\"--help", short_name(spec));
	bash_names(f, spec, false);
	fprintf(f, "%s\"\n\t\tvals=\"", spec->cfg ? " $_stratum_settings" : "");
	bash_names(f, spec, true);
	fprintf(f, "%s\"\n\t\t;;\n", spec->cfg ? " $_stratum_setting_vals" : "");
}

/* zsh: text for inside an _arguments '[...]' description (single-quoted). */
static void zsh_desc(FILE *f, const char *s)
{
	for (; *s && *s != '\n'; s++) {
		if (*s == '\'')
			fputs("'\\''", f);
		else if (*s == ']' || *s == '[' || *s == '\\')
			fprintf(f, "\\%c", *s);
		else
			fputc(*s, f);
	}
}

/* zsh: one _arguments spec for o. */
static void zsh_opt(FILE *f, const struct cmd_opt *o, bool repeat)
{
	char text[CMD_HELP_MAX];
	const char *action = "_files";

	cmd_opt_help(o, text, sizeof(text));
	fputs(" \\\n\t\t\t", f);
	if (o->letter)
		fprintf(f, "'(-%c %s)'{-%c,%s}'", o->letter, o->name, o->letter, o->name);
	else
		fprintf(f, "'%s%s", repeat ? "*" : "", o->name);
	fputc('[', f);
	zsh_desc(f, text);
	fputc(']', f);
	if (!strcmp(o->name, "--printer") || !strcmp(o->name, "--show"))
		action = "_stratum_printers";
	else if (o->kind != CMD_STRING)
		action = ""; /* a number or X,Y: the message alone */
	if (o->kind != CMD_FLAG)
		fprintf(f, ":%s:%s", o->arg ? o->arg : "VALUE", action);
	fputc('\'', f);
}

static void zsh_branch(const struct cmd_spec *spec, FILE *f)
{
	size_t no;
	const struct cmd_opt *cfg = cfgopt_options(&no);

	fprintf(f, "\t(%s)\n\t\t_arguments -s", short_name(spec));
	for (size_t k = 0; k < spec->nopt; k++)
		zsh_opt(f, &spec->opt[k], false);
	if (spec->cfg) {
		for (size_t k = 0; k + 1 < no; k++)
			zsh_opt(f, &cfg[k], true);
		fputs(" \\\n\t\t\t\"${_stratum_settings[@]}\"", f);
	}
	fputs(" \\\n\t\t\t'*:file:_files'\n\t\t;;\n", f);
}

/* The table for tests/check_help.c: NAME, -L or -, flag|value|optional. */
static void option_lines(const struct cmd_spec *spec, FILE *f)
{
	size_t no;
	const struct cmd_opt *cfg = cfgopt_options(&no);

	for (size_t k = 0; k < spec->nopt; k++) {
		const struct cmd_opt *o = &spec->opt[k];

		char letter[3] = {'-', o->letter, '\0'};

		fprintf(f, "%s\t%s\t%s\t%s\n", o->name, letter,
			o->kind == CMD_FLAG		 ? "flag"
			: (o->flags & CMD_OPTIONAL) ? "optional"
						    : "value",
			o->help && *o->help ? "help" : "nohelp");
	}
	for (size_t k = 0; spec->cfg && k + 1 < no; k++)
		fprintf(f, "%s\t-\tvalue\thelp\n", cfg[k].name);
}

int cmd_describe(const struct cmd_spec *spec, const char *format, FILE *f)
{
	if (!strcmp(format, "man"))
		man_body(spec, f);
	else if (!strcmp(format, "bash"))
		bash_branch(spec, f);
	else if (!strcmp(format, "zsh"))
		zsh_branch(spec, f);
	else if (!strcmp(format, "options"))
		option_lines(spec, f);
	else {
		fprintf(stderr, "%s: --help=%s: not man, bash, zsh or options\n", spec->cmd, format);
		return -1;
	}
	return 0;
}

/* ---------------------------------------------------------------------------
 * stratum help
 */

/* cmd's table described as format (cmd_describe, through its parser). */
static int describe(const struct cmd_entry *cmd, const char *format)
{
	char opt[32], name[32];
	char *argv[] = {name, opt, NULL};

	snprintf(name, sizeof(name), "%s", cmd->name);
	snprintf(opt, sizeof(opt), *format ? "--help=%s" : "--help", format);
	return cmd->run(2, argv);
}

/* stratum(1): the commands, each pointing at its own page. */
static void man_overview(const struct cmd_entry *cmds, size_t n, FILE *f)
{
	fputs(".TH STRATUM 1 \"\" \"stratum " STRATUM_VERSION "\" \"User Commands\"\n"
	      ".SH NAME\nstratum \\- repair, slice and print 3D models on FFF printers\n"
	      ".SH SYNOPSIS\n\\fBstratum\\fR \\fICOMMAND\\fR [\\fIOPTIONS\\fR]\n"
	      ".br\n\\fBstratum help\\fR [\\fICOMMAND\\fR]\n"
	      ".br\n\\fBstratum \\-\\-version\\fR\n"
	      ".SH DESCRIPTION\nOne program from a downloaded STL to a print: an exact repair, "
	      "a slicer, and a host that streams G-code (Marlin) or X3G (Sailfish) to the "
	      "printer over USB serial, or to a built-in simulated printer; and a farm node "
	      "with an OctoPrint-compatible API.\n.SH COMMANDS\n", f);
	for (size_t i = 0; i < n; i++) {
		fprintf(f, ".TP\n\\fBstratum\\-%s\\fR(1)\n", cmds[i].name);
		roff_str(f, cmds[i].summary);
		fputc('\n', f);
	}
	fputs(".SH ENVIRONMENT\n.TP\n\\fBSTRATUM_PRINTERS_DIR\\fR\n"
	      "a folder of printer profiles searched first\n"
	      ".TP\n\\fBXDG_CONFIG_HOME\\fR\n"
	      "your own profiles are in $XDG_CONFIG_HOME/stratum/printers "
	      "(default ~/.config/stratum/printers), searched before the installed ones in "
	      "PREFIX/share/stratum/printers\n"
	      ".SH EXIT STATUS\n0 ok, 1 the job failed, 2 usage, 65 bad input data, 69 printer "
	      "unavailable, 70 internal error, 130 interrupted.\n"
	      ".SH SEE ALSO\n", f);
	for (size_t i = 0; i < n; i++)
		fprintf(f, "%s\\fBstratum\\-%s\\fR(1)", i ? ", " : "", cmds[i].name);
	fputs("\n", f);
}

/* stratum-CMD(1): the header and NAME, then the command's own body. */
static int man_page(const struct cmd_entry *cmd)
{
	char upper[32];
	size_t i;

	for (i = 0; cmd->name[i] && i + 1 < sizeof(upper); i++)
		upper[i] = (char)toupper((unsigned char)cmd->name[i]);
	upper[i] = '\0';
	printf(".TH STRATUM-%s 1 \"\" \"stratum " STRATUM_VERSION "\" \"User Commands\"\n"
	       ".SH NAME\nstratum\\-%s \\- ",
	       upper, cmd->name);
	roff_str(stdout, cmd->summary);
	printf("\n");
	fflush(stdout);
	return describe(cmd, "man");
}

/* Where cfgopt_each_setting's callbacks write. */
struct each_ctx {
	FILE *f;
	bool vals; /* bash: only the options that take a value */
};

/* Every setting's --KEY-NAME for a shell list: bash words. */
static void each_bash(const char *opt, bool flag, const char *help, void *ctx)
{
	const struct each_ctx *e = ctx;

	(void)help;
	if (!e->vals || !flag)
		fprintf(e->f, " %s", opt);
}

/* Every setting's --KEY-NAME for zsh: an _arguments spec. */
static void each_zsh(const char *opt, bool flag, const char *help, void *ctx)
{
	const struct each_ctx *e = ctx;

	fprintf(e->f, "\t'%s[", opt);
	zsh_desc(e->f, help && *help ? help : opt + 2);
	fprintf(e->f, "]%s'\n", flag ? "" : ":VALUE:");
}

/* The frame around the commands' branches (head: before them), bash. */
static void bash_frame(const struct cmd_entry *cmds, size_t n, bool head, FILE *f)
{
	struct each_ctx e = {f, false};

	if (!head) {
		fputs("\tesac\n"
		      "\tcase \" $vals \" in *\" $prev \"*)\n"
		      "\t\tcase $prev in --printer|--show)\n"
		      "\t\t\tCOMPREPLY=($(compgen -W \"$(_stratum_printers)\" -- \"$cur\"));;\n"
		      "\t\t*) COMPREPLY=($(compgen -f -- \"$cur\"));; esac\n"
		      "\t\treturn;;\n\tesac\n"
		      "\tif [[ $cur == -* ]]; then\n"
		      "\t\tCOMPREPLY=($(compgen -W \"$opts\" -- \"$cur\"))\n"
		      "\telse\n\t\tCOMPREPLY=($(compgen -f -- \"$cur\"))\n\tfi\n}\n"
		      "complete -o filenames -F _stratum stratum\n", f);
		return;
	}
	fputs("# bash completion for stratum, generated by 'stratum help --completion bash'\n"
	      "# from the option tables the commands parse (do not edit).\n", f);
	fputs("_stratum_settings='", f);
	cfgopt_each_setting(each_bash, &e);
	fputs("'\n_stratum_setting_vals='", f);
	e.vals = true;
	cfgopt_each_setting(each_bash, &e);
	fputs("'\n", f);
	fputs("_stratum_printers() {\n"
	      "\t\"${COMP_WORDS[0]}\" printers 2>/dev/null | awk 'NR > 1 { print $1 }'\n}\n"
	      "_stratum() {\n"
	      "\tlocal cur=${COMP_WORDS[COMP_CWORD]} prev=${COMP_WORDS[COMP_CWORD-1]}\n"
	      "\tlocal opts= vals=\n"
	      "\tCOMPREPLY=()\n"
	      "\tif [ \"$COMP_CWORD\" -eq 1 ]; then\n"
	      "\t\tCOMPREPLY=($(compgen -W '--help --version help",
	      f);
	for (size_t i = 0; i < n; i++)
		fprintf(f, " %s", cmds[i].name);
	fputs("' -- \"$cur\"))\n\t\treturn\n\tfi\n"
	      "\tcase ${COMP_WORDS[1]} in\n"
	      "\thelp)\n\t\tCOMPREPLY=($(compgen -W '",
	      f);
	for (size_t i = 0; i < n; i++)
		fprintf(f, "%s%s", i ? " " : "", cmds[i].name);
	fputs("' -- \"$cur\"))\n\t\treturn;;\n", f);
}

/* The same for zsh. */
static void zsh_frame(const struct cmd_entry *cmds, size_t n, bool head, FILE *f)
{
	struct each_ctx e = {f, false};

	if (!head) {
		fputs("\tesac\n}\n\n_stratum \"$@\"\n", f);
		return;
	}
	fputs("#compdef stratum\n"
	      "# zsh completion for stratum, generated by 'stratum help --completion zsh'\n"
	      "# from the option tables the commands parse (do not edit).\n"
	      "_stratum_printers() {\n"
	      "\tlocal -a p\n"
	      "\tp=(${(f)\"$(_call_program printers stratum printers 2>/dev/null | "
	      "awk 'NR > 1 { print $1 }')\"})\n"
	      "\tcompadd -a p\n}\n\n"
	      "_stratum_settings=(\n",
	      f);
	cfgopt_each_setting(each_zsh, &e);
	fputs(")\n\n_stratum() {\n\tlocal -a commands\n\tcommands=(\n", f);
	for (size_t i = 0; i < n; i++) {
		char item[200];

		snprintf(item, sizeof(item), "%s:%s", cmds[i].name, cmds[i].summary);
		fputs("\t\t", f);
		sh_quote(f, item);
		fputc('\n', f);
	}
	fputs("\t)\n"
	      "\tif (( CURRENT == 2 )); then\n"
	      "\t\t_describe -t commands command commands\n\t\treturn\n\tfi\n"
	      "\tlocal cmd=$words[2]\n\tshift words\n\t(( CURRENT-- ))\n"
	      "\tcase $cmd in\n"
	      "\t(help)\n\t\t_describe -t commands command commands\n\t\t;;\n",
	      f);
}

int cmd_help(const struct cmd_entry *cmds, size_t n, int argc, char **argv)
{
	const char *a = argc > 1 ? argv[1] : NULL, *b = argc > 2 ? argv[2] : NULL;
	const struct cmd_entry *cmd = NULL;
	const char *name = a && a[0] != '-' ? a : b;
	int rc = 0;

	if (!a) {
		cmd_overview(cmds, n, stdout);
		return ST_EXIT_OK;
	}
	if (!strcmp(a, "--commands")) {
		for (size_t i = 0; i < n; i++)
			printf("%s\n", cmds[i].name);
		return ST_EXIT_OK;
	}
	if (!strcmp(a, "--completion")) {
		bool bash = b && !strcmp(b, "bash"), zsh = b && !strcmp(b, "zsh");

		if (!bash && !zsh)
			return cmd_fail(HELP_CMD, ST_EXIT_USAGE, "--completion takes bash or zsh");
		(bash ? bash_frame : zsh_frame)(cmds, n, true, stdout);
		for (size_t i = 0; i < n && !rc; i++) {
			fflush(stdout);
			rc = describe(&cmds[i], bash ? "bash" : "zsh");
		}
		fflush(stdout);
		(bash ? bash_frame : zsh_frame)(cmds, n, false, stdout);
		return rc;
	}
	for (size_t i = 0; name && i < n; i++)
		if (!strcmp(name, cmds[i].name))
			cmd = &cmds[i];
	if (name && !cmd)
		return cmd_fail(HELP_CMD, ST_EXIT_USAGE,
				"no command '%s'; 'stratum help' lists them", name);
	if (!strcmp(a, "--man")) {
		if (!cmd) {
			man_overview(cmds, n, stdout);
			return ST_EXIT_OK;
		}
		return man_page(cmd);
	}
	if (!strcmp(a, "--options") && cmd)
		return describe(cmd, "options");
	if (a[0] == '-' || argc > 2)
		return cmd_fail(HELP_CMD, ST_EXIT_USAGE, "usage: stratum help [COMMAND]");
	return describe(cmd, "");
}
