/*
 * check_install.c - `make install` and `make uninstall` (Makefile): into a
 * DESTDIR staging tree, the installed binary run from another directory
 * finds its profiles under PREFIX/share/stratum/printers (host/profile.h)
 * and slices; the unit names the installed binary and passes
 * `systemd-analyze verify`; uninstall leaves no file behind; `make deb`
 * packages the same tree.  The binary
 * installed is the one under test ($STRATUM_BIN's build folder).
 */
#include <check.h>
#include <libgen.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>

#include "commands.h"
#include "suites.h"
#include "testutil.h"

static char out[1 << 16];

/* "make -s TARGET ARGS" in the source tree for the build folder under test,
 * outside the make that runs the tests (its jobserver is not ours). */
static int make(const char *target, const char *args)
{
	char bin[1024];

	snprintf(bin, sizeof(bin), "%s", tu_bin());
	return tu_sh(out, sizeof(out),
		     "env -u MAKEFLAGS -u MFLAGS -u MAKELEVEL make -s %s BUILD='%s' %s", target,
		     dirname(bin), args);
}

/* The environment of a user with no profiles of their own. */
#define CLEAN_ENV "env -u STRATUM_PRINTERS_DIR -u XDG_CONFIG_HOME STRATUM_VENDOR_DIR=/nonexistent"

START_TEST(install_into_destdir_and_run_there)
{
	char stage[512], root[600], home[512], away[512], args[1200];
	static const char *const files[] = {
	    "bin/stratum", "share/stratum/printers/prusa-i3-mk3s.ini",
	    "share/stratum/printers/flashforge-creator-pro.ini", "share/man/man1/stratum.1",
	    "share/man/man1/stratum-slice.1", "share/man/man1/stratum-serve.1",
	    "share/bash-completion/completions/stratum", "share/zsh/vendor-completions/_stratum",
	    "lib/systemd/system/stratum-serve.service", "share/doc/stratum/README.md",
	    "share/doc/stratum/serve.md", "share/doc/stratum/examples/bracket.stl"};
	char path[800];
	size_t len;
	char *unit;

	snprintf(stage, sizeof(stage), "%s", tu_path("stage"));
	snprintf(root, sizeof(root), "%s/usr", stage);
	snprintf(home, sizeof(home), "%s", tu_path("home"));
	snprintf(away, sizeof(away), "%s", tu_path("elsewhere"));
	ck_assert_int_eq(tu_sh(out, sizeof(out), "mkdir -p '%s' '%s'", home, away), 0);
	snprintf(args, sizeof(args), "DESTDIR='%s' PREFIX=/usr", stage);
	ck_assert_msg(make("install", args) == 0, "make install %s: %s", args, out);
	for (size_t i = 0; i < sizeof(files) / sizeof(files[0]); i++) {
		snprintf(path, sizeof(path), "%s/%s", root, files[i]);
		ck_assert_msg(tu_file_exists(path), "make install wrote no %s", path);
	}
	/* The unit runs the binary where PREFIX puts it, and does not restart
	 * on a config error (exit 2 or 65, docs/errors.md). */
	snprintf(path, sizeof(path), "%s/lib/systemd/system/stratum-serve.service", root);
	unit = tu_slurp(path, &len);
	ck_assert_msg(strstr(unit, "\nExecStart=/usr/bin/stratum serve "), "%s", unit);
	ck_assert_msg(strstr(unit, "\nRestartPreventExitStatus=2 65\n"), "%s", unit);
	free(unit);

	/* From another directory, with no profiles of the user's: the installed
	 * ones are found beside the binary. */
	ck_assert_int_eq(tu_sh(out, sizeof(out), "cd '%s' && " CLEAN_ENV " HOME='%s' '%s/bin/stratum' "
			       "printers --json", away, home, root), 0);
	snprintf(path, sizeof(path), "\"path\": \"%s/share/stratum/printers/prusa-i3-mk3s.ini\"",
		 root);
	ck_assert_msg(strstr(out, path), "wanted %s in: %.2000s", path, out);
	ck_assert_int_eq(tu_sh(out, sizeof(out), "cd '%s' && " CLEAN_ENV " HOME='%s' '%s/bin/stratum' "
			       "slice '%s/share/doc/stratum/examples/bracket.stl' -o bracket.gcode "
			       "--printer prusa-i3-mk3s", away, home, root, root), 0);
	snprintf(path, sizeof(path), "%s/bracket.gcode", away);
	ck_assert_msg(tu_file_exists(path), "%s", out);
	/* man finds the installed pages */
	if (tu_sh(out, sizeof(out), "command -v man") == 0) {
		ck_assert_msg(tu_sh(out, sizeof(out), "MANPATH='%s/share/man' man -w stratum-print",
				    root) == 0, "%s", out);
		ck_assert_msg(strstr(out, "/share/man/man1/stratum-print.1"), "%s", out);
	}

	ck_assert_msg(make("uninstall", args) == 0, "make uninstall: %s", out);
	ck_assert_int_eq(tu_sh(out, sizeof(out), "find '%s' -type f", stage), 0);
	ck_assert_msg(!*out, "make uninstall left: %s", out);
}
END_TEST

/* Installed without DESTDIR (PREFIX alone), the unit's binary exists, so
 * systemd-analyze can verify the unit as systemd would load it. */
START_TEST(installed_unit_verifies)
{
	char prefix[512], args[600];

	snprintf(prefix, sizeof(prefix), "%s", tu_path("prefix"));
	snprintf(args, sizeof(args), "PREFIX='%s'", prefix);
	ck_assert_msg(make("install", args) == 0, "make install %s: %s", args, out);
	if (tu_sh(out, sizeof(out), "command -v systemd-analyze") != 0) {
		fprintf(stderr, "install: systemd-analyze is not installed; unit not verified\n");
	} else {
		ck_assert_msg(tu_sh(out, sizeof(out), "systemd-analyze verify "
				    "'%s/lib/systemd/system/stratum-serve.service'", prefix) == 0,
			      "systemd-analyze verify: %s", out);
		ck_assert_msg(!*out, "systemd-analyze verify: %s", out);
	}
	ck_assert_msg(make("uninstall", args) == 0, "make uninstall: %s", out);
}
END_TEST

/* make deb: a package of the /usr install whose Depends names the
 * libraries' packages, and whose extracted binary runs. */
START_TEST(deb_package)
{
	char bin[1024], deb[1200], x[512];

	if (tu_sh(out, sizeof(out), "command -v dpkg-deb && command -v objdump") != 0) {
		fprintf(stderr, "install: dpkg-deb or objdump missing; make deb not tried\n");
		return;
	}
	ck_assert_msg(make("deb", "") == 0, "make deb: %s", out);
	snprintf(bin, sizeof(bin), "%s", tu_bin());
	snprintf(deb, sizeof(deb), "%s/stratum_" STRATUM_VERSION "_$(dpkg --print-architecture).deb",
		 dirname(bin));
	ck_assert_msg(tu_sh(out, sizeof(out), "dpkg-deb -f %s Package Depends", deb) == 0, "%s",
		      out);
	ck_assert_msg(strstr(out, "Package: stratum\n"), "%s", out);
	ck_assert_msg(strstr(out, "libserialport0") && strstr(out, "libc6"), "%s", out);
	ck_assert_int_eq(tu_sh(out, sizeof(out), "dpkg-deb -c %s", deb), 0);
	ck_assert_msg(strstr(out, " ./usr/bin/stratum\n") &&
			  strstr(out, " ./usr/share/stratum/printers/prusa-i3-mk3s.ini\n") &&
			  strstr(out, " ./usr/lib/systemd/system/stratum-serve.service\n") &&
			  strstr(out, " ./usr/share/man/man1/stratum-print.1\n"),
		      "%s", out);
	snprintf(x, sizeof(x), "%s", tu_path("deb-x"));
	ck_assert_int_eq(tu_sh(out, sizeof(out), "dpkg-deb -x %s '%s' && cd / && " CLEAN_ENV
			       " HOME=/nonexistent '%s/usr/bin/stratum' printers", deb, x, x), 0);
	ck_assert_msg(strstr(out, "prusa-i3-mk3s "), "%s", out);
}
END_TEST

Suite *install_suite(void)
{
	Suite *s = suite_create("install");
	TCase *tc = tcase_create("install");

	tcase_set_timeout(tc, 600);
	tcase_add_test(tc, install_into_destdir_and_run_there);
	tcase_add_test(tc, installed_unit_verifies);
	tcase_add_test(tc, deb_package);
	suite_add_tcase(s, tc);
	return s;
}
