/*
 * fuzz_s3g_frame.c - S3G framing (s3g_frame, serial/s3g.h) on an arbitrary
 * byte stream as the driver meets it: every packet found, every skip
 * honoured; each payload then goes through the command length table and the
 * X3G decoder as the simulator and `stratum x3g --decode` read them.
 */
#include <stddef.h>
#include <stdint.h>

#include "s3g.h"
#include "x3g.h"

int LLVMFuzzerTestOneInput(const uint8_t *data, size_t size);

int LLVMFuzzerTestOneInput(const uint8_t *data, size_t size)
{
	for (size_t at = 0; at < size;) {
		size_t used = 0, plen = 0;
		int rc = s3g_frame(data + at, size - at, &used, &plen);

		if (rc == 0)
			break;
		if (used == 0 || used > size - at)
			__builtin_trap(); /* the contract: progress, within the buffer */
		if (rc > 0 && plen) {
			const uint8_t *p = data + at + 2;
			struct x3g_command cmd;
			struct st_error err = {0};
			char text[512];

			(void)s3g_action_length(p, plen);
			if (x3g_decode(p, plen, at + 2, &cmd, &err) > 0)
				(void)x3g_format(&cmd, text, sizeof(text));
			(void)s3g_rc_name(p[0]);
			(void)s3g_command_name(p[0]);
		}
		at += used;
	}
	return 0;
}
