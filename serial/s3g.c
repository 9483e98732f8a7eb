/*
 * s3g.c - the S3G host driver (s3g.h): the link, exchanges with the retry
 * policy, queries and cancel.  Framing and the code tables are in
 * s3g_frame.c, the build stream and its lost-reply resolver in s3g_stream.c.
 */
#include <stdio.h>
#include <stdlib.h>
#include <string.h>

#include "s3g_int.h"

#define S3G_MAX_TOOLS_OFF 2  /* tools switched off by s3g_cancel */
#define S3G_GARBLED 2	     /* s3g_exchange: bytes came, no valid reply */
#define S3G_PART_MS 100	     /* a reply begun but not complete: the firmware sends
			      * one whole, so a stall this long means its length
			      * byte was damaged */

double s3g_now(struct s3g *s)
{
	return xport_clock_s(s->x);
}

void s3g_sleep_ms(struct s3g *s, int ms)
{
	xport_pause_ms(s->x, ms);
}

static uint16_t s3g_rd16(const uint8_t *p)
{
	return (uint16_t)(p[0] | (p[1] << 8));
}

static uint32_t s3g_rd32(const uint8_t *p)
{
	return (uint32_t)p[0] | (uint32_t)p[1] << 8 | (uint32_t)p[2] << 16 | (uint32_t)p[3] << 24;
}


/* ---- driver ------------------------------------------------------------ */

void s3g_options_init(struct s3g_options *o)
{
	memset(o, 0, sizeof(*o));
	o->timeout_ms = 1000;
	o->max_retries = 5;
	o->max_rejects = 30;
	o->overflow_deadline_ms = 300000;
	o->poll_ms = 5;
	o->stats_ms = 1000;
	o->quiet_ms = 10;
	o->wait_finished = true;
	o->tools = 1;
}

int s3g_new(struct xport *x, const struct s3g_options *opts, struct s3g **out,
	    struct st_error *err)
{
	if (out)
		*out = NULL;
	if (!x || !out)
		return st_error_set(err, ST_ERR_ARG, "s3g_new: no transport");
	struct s3g *s = calloc(1, sizeof(*s));
	if (!s)
		return st_error_set(err, ST_ERR_NOMEM, "S3G driver: out of memory");
	if (opts)
		s->o = *opts;
	else
		s3g_options_init(&s->o);
	if (s->o.timeout_ms <= S3G_PACKET_TIMEOUT_MS || s->o.max_retries < 0 || s->o.max_rejects < 0 ||
	    s->o.poll_ms < 1 || s->o.quiet_ms < 0 || s->o.stats_ms < 1 ||
	    s->o.overflow_deadline_ms < 1) {
		free(s);
		return st_error_set(err, ST_ERR_ARG,
				    "S3G driver: reply time-out must exceed the firmware's %d ms "
				    "packet time-out, and intervals must be positive",
				    S3G_PACKET_TIMEOUT_MS);
	}
	s->x = x;
	s->st.build_state = -1;
	*out = s;
	return 0;
}

void s3g_free(struct s3g *s)
{
	free(s);
}

const struct s3g_status *s3g_status_get(const struct s3g *s)
{
	return &s->st;
}

/* Throw away whatever the printer sent that nobody asked for. */
static int s3g_discard(struct s3g *s, struct st_error *err)
{
	uint8_t junk[256];
	int r;
	s->rx_len = 0;
	while ((r = xport_read(s->x, junk, sizeof(junk), 0, err)) > 0)
		s->st.bytes_in += (uint64_t)r;
	return r < 0 ? r : 0;
}

/* Wait until the line has been silent for quiet_ms, discarding: the
 * firmware answers every noise byte of a damaged packet with its own
 * "generic error" reply, and those must not be taken for the reply to the
 * resend. */
static int s3g_quiet(struct s3g *s, struct st_error *err)
{
	uint8_t junk[256];
	double until = s3g_now(s) + 2.0; /* a babbling line still ends */
	int r;
	s->rx_len = 0;
	while ((r = xport_read(s->x, junk, sizeof(junk), s->o.quiet_ms, err)) > 0) {
		s->st.bytes_in += (uint64_t)r;
		if (s3g_now(s) > until)
			break;
	}
	return r < 0 ? r : 0;
}

int s3g_why(struct s3g *s, enum s3g_fail why, int code)
{
	s->st.fail = why;
	return code;
}

/* The message for a dead link. */
static int s3g_link_error(struct s3g *s, const char *what, struct st_error *err)
{
	char inner[256];
	snprintf(inner, sizeof(inner), "%s", err ? err->msg : "");
	s->st.fail = S3G_FAIL_LINK;
	if (xport_is_gone(s->x))
		return st_error_set(err, ST_ERR_IO,
				    "printer unplugged: %s closed the link during %s",
				    xport_describe(s->x), what);
	return st_error_set(err, ST_ERR_IO, "%s failed: %s", what, inner);
}

/*
 * One packet out, one reply in: returns 1 with the reply payload in resp,
 * 0 if nothing came within the time-out, S3G_GARBLED if bytes came but no
 * valid reply and the line then stayed quiet for quiet_ms (all of them
 * were noise or a frame with a bad CRC) or S3G_PART_MS (a frame begun, not
 * ended): a damaged reply, no use waiting out the time-out for it.  Or < 0
 * on a link error.
 */
static int s3g_exchange(struct s3g *s, const uint8_t *pkt, size_t plen, uint8_t *resp,
			size_t cap, size_t *rlen, const char *what, struct st_error *err)
{
	int r = s3g_discard(s, err);
	if (r < 0)
		return s3g_link_error(s, what, err);
	if (xport_write_all(s->x, pkt, plen, s->o.timeout_ms, NULL, err))
		return s3g_link_error(s, what, err);
	s->st.packets++;
	s->st.bytes_out += plen;
	double end = s3g_now(s) + s->o.timeout_ms / 1000.0;
	bool heard = false; /* bytes came since the packet went out */
	for (;;) {
		size_t used, n;
		int f;
		while ((f = s3g_frame(s->rx, s->rx_len, &used, &n)) != 0) {
			if (f > 0) {
				size_t k = n < cap ? n : cap;
				memcpy(resp, s->rx + 2, k);
				*rlen = k;
				memmove(s->rx, s->rx + used, s->rx_len - used);
				s->rx_len -= used;
				if (n == 0)
					break; /* an empty reply carries no code: ignore */
				return 1;
			}
			memmove(s->rx, s->rx + used, s->rx_len - used);
			s->rx_len -= used;
		}
		double left = end - s3g_now(s);
		if (left <= 0)
			return heard ? S3G_GARBLED : 0;
		if (s->rx_len == sizeof(s->rx))
			s->rx_len = 0;
		int wait_ms = (int)(left * 1000) + 1;
		int settle_ms = s->rx_len ? S3G_PART_MS : s->o.quiet_ms;
		if (heard && wait_ms > settle_ms)
			wait_ms = settle_ms;
		r = xport_read(s->x, s->rx + s->rx_len, sizeof(s->rx) - s->rx_len, wait_ms, err);
		if (r < 0)
			return s3g_link_error(s, what, err);
		if (r == 0 && heard)
			return S3G_GARBLED;
		heard = heard || r > 0;
		s->rx_len += (size_t)r;
		s->st.bytes_in += (uint64_t)r;
	}
}

int s3g_send(struct s3g *s, const uint8_t *payload, size_t len, uint8_t *resp, size_t cap,
	     size_t *rlen, const struct s3g_resolver *res, struct st_error *err)
{
	uint8_t pkt[S3G_MAX_PACKET];
	char what[96];
	int plen = s3g_encode(payload, len, pkt, sizeof(pkt), err);
	int retries = 0, rejects = 0;
	double overflow_since = 0;
	uint32_t last_free = UINT32_MAX;

	if (plen < 0)
		return plen;
	if (cap < 1)
		return st_error_set(err, ST_ERR_ARG, "s3g: reply buffer too small");
	snprintf(what, sizeof(what), "command %u (%s)", payload[0], s3g_command_name(payload[0]));
	for (;;) {
		int r = s3g_exchange(s, pkt, (size_t)plen, resp, cap, rlen, what, err);
		if (r < 0)
			return r;
		if (r == 0 || r == S3G_GARBLED) {
			/* silence bounds the tries (a dead link); damaged
			 * replies are the printer answering through noise, so
			 * they count as rejects (at 2 % of reply bytes spoilt a
			 * build-statistics query got six in a row) */
			if (r == 0)
				s->st.timeouts++;
			else
				s->st.garbled++;
			if (r == 0 && ++retries > s->o.max_retries)
				return s3g_why(s, S3G_FAIL_LINK,
					       st_error_set(err, ST_ERR_IO,
							    "no valid reply from the printer on %s "
							    "to %s after %d tries of %d ms",
							    xport_describe(s->x), what, retries,
							    s->o.timeout_ms));
			if (r == S3G_GARBLED && ++rejects > s->o.max_rejects)
				return s3g_why(s, S3G_FAIL_LINK,
					       st_error_set(err, ST_ERR_IO,
							    "every reply from the printer on %s to "
							    "%s came damaged (%d tries): check the "
							    "cable and the baud rate",
							    xport_describe(s->x), what, rejects));
			s->st.retries++;
			if (s3g_quiet(s, err) < 0)
				return s3g_link_error(s, what, err);
			if (res) {
				int rc = 0;
				enum s3g_lost d = res->decide(s, res->ctx, err, &rc);
				if (rc < 0)
					return rc;
				if (d == S3G_LOST_QUEUED)
					return 1;
			}
			continue;
		}
		uint8_t code = resp[0];
		if (code != S3G_RC_OK)
			s->st.errors++;
		if (code == S3G_RC_OK && (payload[0] & 0x80) && *rlen > 1) {
			/* an action's success carries nothing: data means the
			 * firmware read a query, the packet damaged where CRC-8
			 * cannot see (two bit errors 127 bits apart); it never
			 * queued the action, so it goes again */
			s->st.misread++;
			code = S3G_RC_GENERIC_ERROR;
		}
		switch (s3g_rc_action(code)) {
		case S3G_ACT_NEXT:
		case S3G_ACT_SKIP:
			return 0;
		case S3G_ACT_WAIT_RESEND: {
			s->st.overflows++;
			double now = s3g_now(s);
			if (overflow_since == 0)
				overflow_since = now;
			/* progress: the free space moved since the last look */
			uint8_t q = S3G_Q_BUFFER_FREE, qr[8], qp[4];
			size_t qn;
			s3g_sleep_ms(s, s->o.poll_ms);
			int ql = s3g_encode(&q, 1, qp, sizeof(qp), NULL);
			int e = s3g_exchange(s, qp, (size_t)ql, qr, sizeof(qr), &qn, what, err);
			if (e < 0)
				return e;
			if (e == 1 && qr[0] == S3G_RC_OK && qn >= 5) {
				uint32_t f = s3g_rd32(qr + 1);
				s->st.buffer_free = f;
				if (f != last_free)
					overflow_since = s3g_now(s);
				last_free = f;
			}
			if ((s3g_now(s) - overflow_since) * 1000.0 > s->o.overflow_deadline_ms)
				return s3g_why(s, S3G_FAIL_PRINTER,
					       st_error_set(err, ST_ERR_IO,
							    "the printer's command buffer stayed full "
							    "for %d ms without draining while sending %s",
							    s->o.overflow_deadline_ms, what));
			continue;
		}
		case S3G_ACT_RETRY:
			break;
		case S3G_ACT_FAIL:
			if (code == S3G_RC_QUERY_TOO_BIG && len <= S3G_MAX_PAYLOAD)
				break; /* our length was fine: noise changed it */
			if (code < S3G_RC_GENERIC_ERROR || code > S3G_RC_PACKET_TIMEOUT)
				break; /* no such code: noise that CRC-8 missed */
			return s3g_why(s, S3G_FAIL_PRINTER,
				       st_error_set(err, ST_ERR_IO,
						    "the printer answered %s with 0x%02X (%s)", what,
						    code, s3g_rc_name(code)));
		case S3G_ACT_STOP:
			return s3g_why(s, S3G_FAIL_PRINTER,
				       st_error_set(err, ST_ERR_IO,
						    "the printer stopped the build: it answered %s "
						    "with 0x%02X (%s)",
						    what, code, s3g_rc_name(code)));
		}
		if (++rejects > s->o.max_rejects)
			return s3g_why(s, S3G_FAIL_LINK,
				       st_error_set(err, ST_ERR_IO,
						    "the printer kept rejecting %s: last reply 0x%02X "
						    "(%s) after %d tries",
						    what, code, s3g_rc_name(code), rejects));
		s->st.retries++;
		if (s3g_quiet(s, err) < 0)
			return s3g_link_error(s, what, err);
		/* the error may have been a late reply to an earlier, damaged
		 * copy while this copy was queued: ask before resending */
		if (res) {
			int rc = 0;
			enum s3g_lost d = res->decide(s, res->ctx, err, &rc);
			if (rc < 0)
				return rc;
			if (d == S3G_LOST_QUEUED)
				return 1;
		}
	}
}

int s3g_transact(struct s3g *s, const uint8_t *payload, size_t len, uint8_t *resp, size_t cap,
		 size_t *rlen, struct st_error *err)
{
	if (!s || !payload || !resp || !rlen)
		return st_error_set(err, ST_ERR_ARG, "s3g_transact: NULL argument");
	int r = s3g_send(s, payload, len, resp, cap, rlen, NULL, err);
	return r > 0 ? 0 : r;
}

/* Times a query is asked again after a reply too short for it. */
#define S3G_SHORT_REPLY_RETRIES 3

/* A query whose reply must carry at least need bytes after the code.  A
 * short reply is asked again: a query spoilt on the line whose CRC-8 still
 * matched runs as another query (a link at 1 % of bytes hit, now and then),
 * and a query changes nothing in the printer. */
static int s3g_query(struct s3g *s, const uint8_t *q, size_t qlen, uint8_t *resp, size_t need,
		     struct st_error *err)
{
	uint8_t r[S3G_MAX_PAYLOAD];
	size_t n = 0;

	for (int attempt = 0;; attempt++) {
		int rc = s3g_transact(s, q, qlen, r, sizeof(r), &n, err);
		if (rc)
			return rc;
		if (r[0] != S3G_RC_OK)
			return st_error_set(err, ST_ERR_IO,
					    "the printer does not support %s (0x%02X)",
					    s3g_command_name(q[0]), r[0]);
		if (n >= need + 1)
			break;
		if (attempt == S3G_SHORT_REPLY_RETRIES)
			return st_error_set(err, ST_ERR_RANGE,
					    "reply to %s has %zu bytes, expected %zu (asked %d times)",
					    s3g_command_name(q[0]), n, need + 1, attempt + 1);
	}
	memcpy(resp, r + 1, need);
	return 0;
}

int s3g_get_version(struct s3g *s, uint16_t host_version, uint16_t *fw, struct st_error *err)
{
	uint8_t q[3] = {S3G_Q_VERSION, (uint8_t)host_version, (uint8_t)(host_version >> 8)}, r[2];
	int rc = s3g_query(s, q, 3, r, 2, err);
	if (!rc)
		*fw = s3g_rd16(r);
	return rc;
}

int s3g_get_buffer_free(struct s3g *s, uint32_t *free_bytes, struct st_error *err)
{
	uint8_t q = S3G_Q_BUFFER_FREE, r[4];
	int rc = s3g_query(s, &q, 1, r, 4, err);
	if (!rc) {
		*free_bytes = s3g_rd32(r);
		s->st.buffer_free = *free_bytes;
	}
	return rc;
}

/* Tool query (10) returning an int16. */
static int s3g_tool_i16(struct s3g *s, uint8_t tool, uint8_t cmd, int *out, struct st_error *err)
{
	uint8_t q[3] = {S3G_Q_TOOL_QUERY, tool, cmd}, r[2];
	int rc = s3g_query(s, q, 3, r, 2, err);
	if (!rc)
		*out = (int16_t)s3g_rd16(r);
	return rc;
}

int s3g_get_temps(struct s3g *s, struct s3g_temps *t, struct st_error *err)
{
	int rc;
	if ((rc = s3g_tool_i16(s, 0, S3G_TQ_TEMP, &t->tool, err)) ||
	    (rc = s3g_tool_i16(s, 0, S3G_TQ_TARGET, &t->tool_target, err)) ||
	    (rc = s3g_tool_i16(s, 0, S3G_TQ_PLATFORM_TEMP, &t->platform, err)) ||
	    (rc = s3g_tool_i16(s, 0, S3G_TQ_PLATFORM_TARGET, &t->platform_target, err)))
		return rc;
	t->tool1 = t->tool1_target = 0;
	if (s->o.tools > 1 &&
	    ((rc = s3g_tool_i16(s, 1, S3G_TQ_TEMP, &t->tool1, err)) ||
	     (rc = s3g_tool_i16(s, 1, S3G_TQ_TARGET, &t->tool1_target, err))))
		return rc;
	s->st.tool1_temp = t->tool1;
	s->st.tool1_target = t->tool1_target;
	s->st.tool_temp = t->tool;
	s->st.tool_target = t->tool_target;
	s->st.platform_temp = t->platform;
	s->st.platform_target = t->platform_target;
	return 0;
}

int s3g_is_finished(struct s3g *s, bool *done, struct st_error *err)
{
	uint8_t q = S3G_Q_IS_FINISHED, r[1];
	int rc = s3g_query(s, &q, 1, r, 1, err);
	if (!rc)
		*done = r[0] != 0;
	return rc;
}

int s3g_get_position(struct s3g *s, struct s3g_position *p, struct st_error *err)
{
	uint8_t q = S3G_Q_POSITION_EXT, r[22];
	int rc = s3g_query(s, &q, 1, r, 22, err);
	if (rc)
		return rc;
	for (int i = 0; i < 5; i++)
		p->steps[i] = (int32_t)s3g_rd32(r + 4 * i);
	p->endstops = s3g_rd16(r + 20);
	return 0;
}

int s3g_get_build_stats(struct s3g *s, struct s3g_build_stats *b, struct st_error *err)
{
	uint8_t q[2] = {S3G_Q_BUILD_STATS, 0}, r[11];
	int rc = s3g_query(s, q, 2, r, 7, err);
	if (rc)
		return rc;
	b->state = r[0];
	b->hours = r[1];
	b->minutes = r[2];
	b->line = s3g_rd32(r + 3);
	s->st.build_state = b->state;
	s->st.line = b->line;
	return 0;
}

int s3g_get_board_status(struct s3g *s, uint8_t *bits, struct st_error *err)
{
	uint8_t q = S3G_Q_BOARD_STATUS;
	return s3g_query(s, &q, 1, bits, 1, err);
}

int s3g_cancel(struct s3g *s, struct st_error *err)
{
	uint8_t r[S3G_MAX_PAYLOAD];
	size_t n;
	int first = 0, rc;
	uint8_t abort_q = S3G_Q_ABORT;

	rc = s3g_transact(s, &abort_q, 1, r, sizeof(r), &n, err);
	if (rc)
		return rc; /* without the abort, heaters-off would queue behind moves */
	/* the board resets once the reply is out; give it that moment */
	s3g_sleep_ms(s, 50);
	for (uint8_t t = 0; t < S3G_MAX_TOOLS_OFF; t++) {
		uint8_t off[6] = {136, t, S3G_TA_SET_TEMP, 2, 0, 0};
		rc = s3g_transact(s, off, sizeof(off), r, sizeof(r), &n, err);
		if (rc && !first)
			first = rc;
	}
	uint8_t bed[6] = {136, 0, S3G_TA_SET_PLATFORM_TEMP, 2, 0, 0};
	rc = s3g_transact(s, bed, sizeof(bed), r, sizeof(r), &n, err);
	if (rc && !first)
		first = rc;
	uint8_t motors[2] = {137, 0x1F}; /* bit 7 clear: disable X Y Z A B */
	rc = s3g_transact(s, motors, sizeof(motors), r, sizeof(r), &n, err);
	if (rc && !first)
		first = rc;
	return first;
}
