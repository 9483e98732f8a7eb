/*
 * s3g_int.h - what the S3G driver's parts share: s3g.c (the link,
 * exchanges and queries) and s3g_stream.c (the build stream and its
 * lost-reply resolver); nothing else includes it.  s3g_frame.c needs only
 * s3g.h.  The contract is s3g.h.
 */
#ifndef STRATUM_SERIAL_S3G_INT_H
#define STRATUM_SERIAL_S3G_INT_H

#include <stddef.h>
#include <stdint.h>

#include "s3g.h"

#define S3G_RX_CAP 1024 /* reply bytes kept while framing */

struct s3g {
	struct xport *x;
	struct s3g_options o;
	uint8_t rx[S3G_RX_CAP];
	size_t rx_len;
	struct s3g_status st;
	char frame_name[S3G_FRAME_NAME_MAX + 1]; /* s3g_frame_builds; "" off */
};

/* Outcome of s3g_send for a lost reply, decided by the stream. */
enum s3g_lost { S3G_LOST_RESEND, S3G_LOST_QUEUED };

/* Hook the stream gives s3g_send to settle a lost reply. */
struct s3g_resolver {
	enum s3g_lost (*decide)(struct s3g *s, void *ctx, struct st_error *err, int *rc);
	void *ctx;
};

/* Seconds and sleeps on the transport's clock (xport_clock_s). */
double s3g_now(struct s3g *s);
void s3g_sleep_ms(struct s3g *s, int ms);

/* Record why a call failed (status.fail); returns code, to wrap
 * st_error_set. */
int s3g_why(struct s3g *s, enum s3g_fail why, int code);

/*
 * Send payload with the retry policy.  Returns 0 with resp[0] OK or
 * UNSUPPORTED, 1 when the resolver found an action packet already queued
 * after its reply was lost, or an error.
 */
int s3g_send(struct s3g *s, const uint8_t *payload, size_t len, uint8_t *resp, size_t cap,
	     size_t *rlen, const struct s3g_resolver *res, struct st_error *err);

#endif
