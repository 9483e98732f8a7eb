/*
 * fuzz_s3g_stream.c - the S3G driver (serial/s3g.h) over a transport whose
 * printer says the fuzzer's bytes: version, temperatures, a stream of real
 * action commands with the free-space bookkeeping, and the cancel.  A CRC
 * is too hard for a mutator to guess, so the input is records that this
 * harness frames: a header byte (bit 7: raw noise; bit 6: spoil the CRC;
 * bits 0-5: length) and that many bytes, each record the printer's answer
 * to one packet (an empty one: no answer).  The first byte picks the options.
 */
#include <stddef.h>
#include <stdint.h>
#include <stdlib.h>
#include <string.h>

#include "fuzz.h"
#include "gcode.h"
#include "s3g.h"
#include "x3g.h"

int LLVMFuzzerTestOneInput(const uint8_t *data, size_t size);

/* The action commands streamed: a short build, translated once. */
static struct s3g_cmd cmds[64];
static size_t ncmds;
static uint8_t cmd_bytes[4096];

static void make_commands(void)
{
	static const char *const gcode[] = {
		"M73 P0", "M104 S200 T0", "G28 X Y", "G92 X0 Y0 Z0 A0 B0", "G1 X10 Y10 F3000",
		"G1 X20 Y5 E1.5 F1800", "M133 T0", "M73 P50", "G4 P100", "M73 P100",
	};
	struct x3g_translator *t;
	struct x3g_machine m;
	struct st_error err = {0};
	size_t used = 0;

	x3g_machine_fcp(&m);
	if (x3g_new(&m, NULL, &t, &err))
		abort();
	for (size_t i = 0; i <= sizeof(gcode) / sizeof(gcode[0]); i++) {
		struct gcode_line g;
		const uint8_t *out;
		size_t len;

		if (i < sizeof(gcode) / sizeof(gcode[0])) {
			if (gcode_parse(gcode[i], strlen(gcode[i]), 0, &g, &err) ||
			    x3g_translate(t, &g, i + 1, &err) < 0)
				abort();
		} else if (x3g_finish(t, &err) < 0) {
			abort();
		}
		out = x3g_output(t, &len);
		for (size_t at = 0; at < len;) {
			int n = s3g_action_length(out + at, len - at);

			if (n <= 0 || n > S3G_MAX_PAYLOAD || used + (size_t)n > sizeof(cmd_bytes) ||
			    ncmds == sizeof(cmds) / sizeof(cmds[0]))
				abort();
			memcpy(cmd_bytes + used, out + at, (size_t)n);
			cmds[ncmds].payload = cmd_bytes + used;
			cmds[ncmds++].len = (uint8_t)n;
			used += (size_t)n;
			at += (size_t)n;
		}
	}
	x3g_free(t);
}

/* The transport of the records of (data, size): one turn per record, the
 * printer's answer to one packet; nothing before the first packet. */
static struct xport *replies(const uint8_t *data, size_t size)
{
	uint8_t *buf = malloc(size * 3 + 8), pkt[S3G_MAX_PACKET];
	size_t *ends = malloc((size + 2) * sizeof(*ends)), n = 0, nturns = 0;
	struct st_error err = {0};
	struct xport *x = NULL;

	if (!buf || !ends)
		goto out_free;
	ends[nturns++] = 0;
	for (size_t at = 0; at < size;) {
		uint8_t h = data[at++];
		size_t len = h & 0x3f;

		if (len > size - at)
			len = size - at;
		if (h & 0x80) {
			memcpy(buf + n, data + at, len);
			n += len;
		} else if (len) {
			int k = s3g_encode(data + at, len > S3G_MAX_PAYLOAD ? S3G_MAX_PAYLOAD : len,
					   pkt, sizeof(pkt), &err);

			if (k > 0) {
				if (h & 0x40)
					pkt[k - 1] ^= 0x5a;
				memcpy(buf + n, pkt, (size_t)k);
				n += (size_t)k;
			}
		}
		at += len;
		ends[nturns++] = n;
	}
	if (ends[nturns - 1] != n)
		ends[nturns++] = n;
	x = fuzz_xport_new(buf, n, ends, nturns);
out_free:
	free(buf);
	free(ends);
	return x;
}

int LLVMFuzzerTestOneInput(const uint8_t *data, size_t size)
{
	struct st_error err = {0};
	struct s3g_options o;
	struct s3g_status st;
	struct s3g *s = NULL;
	struct xport *x;
	uint8_t mode;

	if (!ncmds)
		make_commands();
	if (!size)
		return 0;
	mode = data[0];
	x = replies(data + 1, size - 1);
	if (!x)
		return 0;
	s3g_options_init(&o);
	o.timeout_ms = 250; /* must exceed the firmware's 200 ms; the script never waits */
	o.max_retries = 2;
	o.max_rejects = 3;
	o.overflow_deadline_ms = 100;
	o.poll_ms = 1;
	o.stats_ms = 10;
	o.quiet_ms = 1;
	o.wait_finished = mode & 1;
	if (s3g_new(x, &o, &s, &err))
		goto out_close;
	if (mode & 2) {
		uint16_t fw;
		struct s3g_temps t;
		struct s3g_build_stats b;
		struct s3g_position p;
		uint32_t free_bytes;
		uint8_t bits;
		bool done;

		(void)s3g_get_version(s, 100, &fw, &err);
		(void)s3g_get_buffer_free(s, &free_bytes, &err);
		(void)s3g_get_temps(s, &t, &err);
		(void)s3g_is_finished(s, &done, &err);
		(void)s3g_get_position(s, &p, &err);
		(void)s3g_get_build_stats(s, &b, &err);
		(void)s3g_get_board_status(s, &bits, &err);
	}
	(void)s3g_stream(s, cmds, ncmds, NULL, NULL, NULL, &st, &err);
	if (mode & 4)
		(void)s3g_cancel(s, &err);
	s3g_free(s);
out_close:
	xport_close(x);
	return 0;
}
