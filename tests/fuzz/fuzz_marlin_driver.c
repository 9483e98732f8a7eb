/*
 * fuzz_marlin_driver.c - the Marlin driver (serial/marlin.h) over a
 * transport whose printer says the fuzzer's bytes: connect (banner, M110,
 * M115, capabilities), a short job through the window with resends, busy,
 * errors and temperature reports as they come, then pause, cancel and the
 * safe stop.  The first byte picks the options; the rest is the printer's
 * side of the link in turns separated by the byte 0x1e (TURN): what comes
 * before the first is there at once, each line the host writes lets the
 * next turn through.  When the bytes run out the printer is gone, so every
 * run ends.
 */
#include <math.h>
#include <stddef.h>
#include <stdint.h>
#include <stdlib.h>

#include "fuzz.h"
#include "marlin.h"

int LLVMFuzzerTestOneInput(const uint8_t *data, size_t size);

#define TURN 0x1e

/* The transport of the script (data, size): TURN bytes end turns. */
static struct xport *script(const uint8_t *data, size_t size)
{
	uint8_t *said = malloc(size ? size : 1);
	size_t *ends = malloc((size + 1) * sizeof(*ends)), n = 0, nturns = 0;
	struct xport *x = NULL;

	if (said && ends) {
		for (size_t i = 0; i < size; i++) {
			if (data[i] == TURN)
				ends[nturns++] = n;
			else
				said[n++] = data[i];
		}
		ends[nturns++] = n;
		x = fuzz_xport_new(said, n, ends, nturns);
	}
	free(said);
	free(ends);
	return x;
}

int LLVMFuzzerTestOneInput(const uint8_t *data, size_t size)
{
	static const char *const job[] = {
		"M140 S60", "M104 S200", "G28", "M190 S60", "M109 S200", "G92 E0",
		"G1 Z0.2 F600", "G1 X10 Y10 E1.5 F1200", "M106 S255", "G1 X20 E3",
		"M400", "M105", "M114", "G4 P10", "M107", "M84",
	};
	struct st_error err = {0};
	struct marlin_options o;
	struct marlin *m = NULL;
	struct xport *x;
	uint8_t mode;

	if (!size)
		return 0;
	mode = data[0];
	x = script(data + 1, size - 1);
	if (!x)
		return 0;
	marlin_options_init(&o);
	o.expect_reset = mode & 1;
	o.rx_buffer = (mode & 2) ? 32 : 128;
	o.bufsize = (mode & 4) ? 4 : 0;
	o.autoreport_s = (mode & 8) ? 2 : 0;
	o.boot_wait_ms = o.connect_timeout_ms = 100;
	o.retry_ms = o.probe_ms = 20;
	o.dead_ms = o.dead_blocking_ms = 100;
	if (marlin_new(x, &o, &m, &err))
		goto out_close;
	if (marlin_connect(m, &err))
		goto out_free;
	for (size_t i = 0, steps = 0; steps < 4000; steps++) {
		if (i < sizeof(job) / sizeof(job[0]) && marlin_can_submit(m)) {
			int rc = marlin_submit(m, job[i], i + 1, (long)i / 4, NAN, &err);

			if (rc < 0)
				break;
			i += (size_t)rc;
			continue;
		}
		if (i == 6 && (mode & 16))
			marlin_request_pause(m);
		if (i == 8 && (mode & 16))
			marlin_request_resume(m);
		/* A job paused with all of it submitted (the pause above when
		 * the window stayed open past line 8, or //action:pause) waits
		 * for the user: resume it as one would, instead of stepping a
		 * paused driver to the step limit (3 % of the inputs took 80 %
		 * of the steps that way). */
		if (i == sizeof(job) / sizeof(job[0])) {
			struct marlin_status st;

			marlin_status(m, &st);
			if (st.paused)
				marlin_request_resume(m);
		}
		if (i == 10 && (mode & 32))
			marlin_request_cancel(m);
		/* waits as the sender's do (serial/printer_marlin.c): on the
		 * transport's clock they cost no real time */
		if (marlin_step(m, 50, &err))
			break;
		if (i == sizeof(job) / sizeof(job[0]) && marlin_idle(m))
			break;
	}
	if (mode & 64)
		(void)marlin_emergency(m, "M108", &err);
	if (mode & 128)
		(void)marlin_safe_stop(m, 100, &err);
out_free:
	marlin_free(m);
out_close:
	xport_close(x);
	return 0;
}
