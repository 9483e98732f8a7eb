/*
 * s3g.c - S3G framing, tables and the host driver (see s3g.h).
 */
#include <stdio.h>
#include <stdlib.h>
#include <string.h>
#include <time.h>

#include "s3g.h"
#include "st_clock.h"

#define S3G_RX_CAP 1024	     /* reply bytes kept while framing */
#define S3G_MAX_TOOLS_OFF 2  /* tools switched off by s3g_cancel */
#define S3G_GARBLED 2	     /* s3g_exchange: bytes came, no valid reply */
#define S3G_PART_MS 100	     /* a reply begun but not complete: the firmware sends
			      * one whole, so a stall this long means its length
			      * byte was damaged */

struct s3g {
	struct xport *x;
	struct s3g_options o;
	uint8_t rx[S3G_RX_CAP];
	size_t rx_len;
	struct s3g_status st;
};

static double s3g_now(void)
{
	return st_mono_s();
}

static void s3g_sleep_ms(int ms)
{
	struct timespec ts = {ms / 1000, (long)(ms % 1000) * 1000000L};
	while (nanosleep(&ts, &ts) != 0)
		;
}

static uint16_t s3g_rd16(const uint8_t *p)
{
	return (uint16_t)(p[0] | (p[1] << 8));
}

static uint32_t s3g_rd32(const uint8_t *p)
{
	return (uint32_t)p[0] | (uint32_t)p[1] << 8 | (uint32_t)p[2] << 16 | (uint32_t)p[3] << 24;
}

/* ---- framing ---------------------------------------------------------- */

/* Bitwise form of avr-libc's _crc_ibutton_update. */
uint8_t s3g_crc_update(uint8_t crc, uint8_t byte)
{
	crc ^= byte;
	for (int i = 0; i < 8; i++)
		crc = (crc & 1) ? (uint8_t)((crc >> 1) ^ 0x8C) : (uint8_t)(crc >> 1);
	return crc;
}

uint8_t s3g_crc(const uint8_t *p, size_t n)
{
	uint8_t crc = 0;
	for (size_t i = 0; i < n; i++)
		crc = s3g_crc_update(crc, p[i]);
	return crc;
}

int s3g_encode(const uint8_t *payload, size_t len, uint8_t *out, size_t cap,
	       struct st_error *err)
{
	if (!payload || !out || len == 0 || len > S3G_MAX_PAYLOAD)
		return st_error_set(err, ST_ERR_ARG,
				    "S3G payload of %zu bytes: must be 1 to %d bytes", len,
				    S3G_MAX_PAYLOAD);
	if (cap < len + 3)
		return st_error_set(err, ST_ERR_ARG, "S3G packet buffer too small");
	out[0] = S3G_START;
	out[1] = (uint8_t)len;
	memcpy(out + 2, payload, len);
	out[2 + len] = s3g_crc(payload, len);
	return (int)(len + 3);
}

int s3g_frame(const uint8_t *buf, size_t len, size_t *consumed, size_t *plen)
{
	size_t i = 0;
	*consumed = 0;
	*plen = 0;
	while (i < len && buf[i] != S3G_START)
		i++;
	if (i > 0) {
		*consumed = i;
		return S3G_SKIP_NOISE;
	}
	if (len < 2)
		return 0;
	if (buf[1] > S3G_MAX_PAYLOAD) {
		*consumed = 1;
		return S3G_SKIP_BAD_LENGTH;
	}
	size_t n = buf[1];
	if (len < n + 3)
		return 0;
	if (s3g_crc(buf + 2, n) != buf[2 + n]) {
		*consumed = 1;
		return S3G_SKIP_BAD_CRC;
	}
	*consumed = n + 3;
	*plen = n;
	return 1;
}

/* ---- tables ------------------------------------------------------------ */

enum s3g_action s3g_rc_action(uint8_t rc)
{
	switch (rc) {
	case S3G_RC_OK:
		return S3G_ACT_NEXT;
	case S3G_RC_BUFFER_OVERFLOW:
		return S3G_ACT_WAIT_RESEND;
	case S3G_RC_GENERIC_ERROR:
	case S3G_RC_CRC_MISMATCH:
	case S3G_RC_TOOL_LOCK_TIMEOUT:
	case S3G_RC_PACKET_TIMEOUT:
		return S3G_ACT_RETRY;
	case S3G_RC_UNSUPPORTED:
		return S3G_ACT_SKIP;
	case S3G_RC_CANCEL_BUILD:
	case S3G_RC_BOT_OVERHEAT:
		return S3G_ACT_STOP;
	default:
		return S3G_ACT_FAIL;
	}
}

const char *s3g_rc_name(uint8_t rc)
{
	switch (rc) {
	case S3G_RC_GENERIC_ERROR: return "generic packet error";
	case S3G_RC_OK: return "success";
	case S3G_RC_BUFFER_OVERFLOW: return "buffer overflow";
	case S3G_RC_CRC_MISMATCH: return "CRC mismatch";
	case S3G_RC_QUERY_TOO_BIG: return "packet too big";
	case S3G_RC_UNSUPPORTED: return "command not supported";
	case S3G_RC_EXPECT_MORE: return "expect more";
	case S3G_RC_DOWNSTREAM_TIMEOUT: return "downstream timeout";
	case S3G_RC_TOOL_LOCK_TIMEOUT: return "tool lock timeout";
	case S3G_RC_CANCEL_BUILD: return "build cancelled on the printer";
	case S3G_RC_BOT_BUILDING: return "printer is building from SD card";
	case S3G_RC_BOT_OVERHEAT: return "printer shut down by overheat";
	case S3G_RC_PACKET_TIMEOUT: return "packet timeout";
	default: return "unknown";
	}
}

/* One action command: code, fixed length after the code byte (or -1 for
 * variable), name.  Lengths from the s3g protocol document and the
 * firmware's command parser. */
struct s3g_cmd_info {
	uint8_t code;
	int8_t args;
	const char *name;
};

static const struct s3g_cmd_info s3g_actions[] = {
	{131, 7, "find axes minimums"},
	{132, 7, "find axes maximums"},
	{133, 4, "delay"},
	{134, 1, "change tool"},
	{135, 5, "wait for tool"},
	{136, -1, "tool action"},
	{137, 1, "enable axes"},
	{139, 24, "queue point ext"},
	{140, 20, "set position ext"},
	{141, 5, "wait for platform"},
	{142, 25, "queue point new"},
	{143, 1, "store home positions"},
	{144, 1, "recall home positions"},
	{145, 2, "set pot value"},
	{146, 5, "set RGB LED"},
	{147, 5, "set beep"},
	{148, 4, "wait for button"},
	{149, -1, "display message"},
	{150, 2, "set build percentage"},
	{151, 1, "queue song"},
	{152, 1, "reset to factory"},
	{153, -1, "build start notification"},
	{154, 1, "build end notification"},
	{155, 31, "queue point x3g"},
	{156, 1, "set segment acceleration"},
	{157, 20, "stream version"},
	{158, 4, "pause at Z"},
};

static const struct s3g_cmd_info *s3g_action_info(uint8_t code)
{
	for (size_t i = 0; i < sizeof(s3g_actions) / sizeof(s3g_actions[0]); i++)
		if (s3g_actions[i].code == code)
			return &s3g_actions[i];
	return NULL;
}

const char *s3g_command_name(uint8_t code)
{
	const struct s3g_cmd_info *a = s3g_action_info(code);
	if (a)
		return a->name;
	switch (code) {
	case S3G_Q_VERSION: return "get version";
	case S3G_Q_INIT: return "init";
	case S3G_Q_BUFFER_FREE: return "get buffer size";
	case S3G_Q_CLEAR_BUFFER: return "clear buffer";
	case S3G_Q_ABORT: return "abort";
	case S3G_Q_PAUSE: return "pause";
	case S3G_Q_TOOL_QUERY: return "tool query";
	case S3G_Q_IS_FINISHED: return "is finished";
	case S3G_Q_RESET: return "reset";
	case S3G_Q_BUILD_NAME: return "get build name";
	case S3G_Q_POSITION_EXT: return "get position ext";
	case S3G_Q_EXTENDED_STOP: return "extended stop";
	case S3G_Q_BOARD_STATUS: return "get motherboard status";
	case S3G_Q_BUILD_STATS: return "get build statistics";
	case S3G_Q_ADVANCED_VERSION: return "get advanced version";
	default: return "unknown";
	}
}

int s3g_action_length(const uint8_t *buf, size_t avail)
{
	if (avail < 1)
		return 0;
	const struct s3g_cmd_info *a = s3g_action_info(buf[0]);
	if (!a)
		return ST_ERR_UNSUPPORTED;
	if (a->args >= 0)
		return 1 + a->args;
	if (buf[0] == 136) /* tool, command, length, payload */
		return avail < 4 ? 0 : 4 + buf[3];
	/* 149: options, x, y, timeout, text; 153: uint32, text; both start
	 * at byte 5 and end at their NUL */
	for (size_t i = 5; i < avail; i++)
		if (buf[i] == 0)
			return (int)(i + 1);
	return 0;
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
	double until = s3g_now() + 2.0; /* a babbling line still ends */
	int r;
	s->rx_len = 0;
	while ((r = xport_read(s->x, junk, sizeof(junk), s->o.quiet_ms, err)) > 0) {
		s->st.bytes_in += (uint64_t)r;
		if (s3g_now() > until)
			break;
	}
	return r < 0 ? r : 0;
}

/* Record why a call failed (status.fail); returns code, to wrap
 * st_error_set. */
static int s3g_why(struct s3g *s, enum s3g_fail why, int code)
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
	double end = s3g_now() + s->o.timeout_ms / 1000.0;
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
		double left = end - s3g_now();
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

/* Outcome of s3g_send for a lost reply, decided by the stream. */
enum s3g_lost { S3G_LOST_RESEND, S3G_LOST_QUEUED };

/* Hook the stream gives s3g_send to settle a lost reply. */
struct s3g_resolver {
	enum s3g_lost (*decide)(struct s3g *s, void *ctx, struct st_error *err, int *rc);
	void *ctx;
};

/*
 * Send payload with the retry policy.  Returns 0 with resp[0] OK or
 * UNSUPPORTED, 1 when the resolver found an action packet already queued
 * after its reply was lost, or an error.
 */
static int s3g_send(struct s3g *s, const uint8_t *payload, size_t len, uint8_t *resp,
		    size_t cap, size_t *rlen, const struct s3g_resolver *res,
		    struct st_error *err)
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
			double now = s3g_now();
			if (overflow_since == 0)
				overflow_since = now;
			/* progress: the free space moved since the last look */
			uint8_t q = S3G_Q_BUFFER_FREE, qr[8], qp[4];
			size_t qn;
			s3g_sleep_ms(s->o.poll_ms);
			int ql = s3g_encode(&q, 1, qp, sizeof(qp), NULL);
			int e = s3g_exchange(s, qp, (size_t)ql, qr, sizeof(qr), &qn, what, err);
			if (e < 0)
				return e;
			if (e == 1 && qr[0] == S3G_RC_OK && qn >= 5) {
				uint32_t f = s3g_rd32(qr + 1);
				s->st.buffer_free = f;
				if (f != last_free)
					overflow_since = s3g_now();
				last_free = f;
			}
			if ((s3g_now() - overflow_since) * 1000.0 > s->o.overflow_deadline_ms)
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

/* A query whose reply must carry at least need bytes after the code. */
static int s3g_query(struct s3g *s, const uint8_t *q, size_t qlen, uint8_t *resp, size_t need,
		     struct st_error *err)
{
	uint8_t r[S3G_MAX_PAYLOAD];
	size_t n = 0;
	int rc = s3g_transact(s, q, qlen, r, sizeof(r), &n, err);
	if (rc)
		return rc;
	if (r[0] != S3G_RC_OK)
		return st_error_set(err, ST_ERR_IO, "the printer does not support %s (0x%02X)",
				    s3g_command_name(q[0]), r[0]);
	if (n < need + 1)
		return st_error_set(err, ST_ERR_RANGE,
				    "reply to %s has %zu bytes, expected %zu",
				    s3g_command_name(q[0]), n, need + 1);
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
	s3g_sleep_ms(50);
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

/* ---- streaming ---------------------------------------------------------- */

#define S3G_HIST_MASK (S3G_STREAM_HISTORY - 1)
_Static_assert((S3G_STREAM_HISTORY & S3G_HIST_MASK) == 0, "history must be a power of two");

/* What the stream knows for settling lost replies and spotting resets.
 * Commands are pulled one at a time, so the lengths and codes of the last
 * S3G_STREAM_HISTORY are kept by index: those still queued in the
 * firmware are always among them (a buffer of capacity bytes holds at most
 * capacity / 2 commands). */
struct s3g_stream_ctx {
	size_t n;		/* commands expected, 0 unknown */
	size_t cur;		/* index of the packet in flight */
	long base;		/* index of the last confirmed build start (153), -1 none */
	uint32_t capacity;	/* largest free space seen (bytes) */
	bool seen_running;	/* build statistics said running after our 153 */
	bool running_before;	/* a build ran when the stream began */
	uint32_t last_line;
	double next_stats;
	bool stats_due;		/* check now (after a time-out) */
	uint8_t len[S3G_STREAM_HISTORY];  /* by index & S3G_HIST_MASK */
	uint8_t code[S3G_STREAM_HISTORY];
};

/* The last confirmed command, for messages. */
static void s3g_last_desc(const struct s3g_stream_ctx *c, char *buf, size_t cap)
{
	char of[32] = "";
	if (c->n)
		snprintf(of, sizeof(of), " of %zu", c->n);
	if (c->cur == 0)
		snprintf(buf, cap, "before the first command was confirmed");
	else
		snprintf(buf, cap, "after command %zu%s (code %u, %s) was confirmed", c->cur, of,
			 c->code[(c->cur - 1) & S3G_HIST_MASK],
			 s3g_command_name(c->code[(c->cur - 1) & S3G_HIST_MASK]));
}

/* Build statistics: remember the build running; a reboot shows as state
 * "none" or a line number going backwards.  Returns 0 or ST_ERR_IO. */
static int s3g_check_reset(struct s3g *s, struct s3g_stream_ctx *c, struct s3g_build_stats *out,
			   struct st_error *err)
{
	struct s3g_build_stats b;
	char last[160];
	int rc = s3g_get_build_stats(s, &b, err);
	if (rc)
		return rc;
	c->next_stats = s3g_now() + s->o.stats_ms / 1000.0;
	c->stats_due = false;
	if (out)
		*out = b;
	bool running = b.state == S3G_BUILD_RUNNING || b.state == S3G_BUILD_PAUSED;
	if (c->seen_running &&
	    (b.state == S3G_BUILD_NONE || (running && b.line < c->last_line))) {
		s3g_last_desc(c, last, sizeof(last));
		return s3g_why(s, S3G_FAIL_LINK,
			       st_error_set(err, ST_ERR_IO,
					    "the printer reset during the print: it answers as "
					    "freshly booted (build state %u, line %u, was line %u) "
					    "%s; home it and start the print again",
					    b.state, b.line, c->last_line, last));
	}
	if (running && c->base >= 0) {
		c->seen_running = true;
		c->last_line = b.line;
	}
	return 0;
}

/* Settle a lost reply to command cur (see s3g.h "Exactly once"). */
static enum s3g_lost s3g_decide(struct s3g *s, void *ctx, struct st_error *err, int *rc)
{
	struct s3g_stream_ctx *c = ctx;
	struct s3g_build_stats b;
	uint32_t f1 = 0, f2 = 1;

	*rc = s3g_check_reset(s, c, &b, err);
	if (*rc)
		return S3G_LOST_RESEND;
	bool running = b.state == S3G_BUILD_RUNNING || b.state == S3G_BUILD_PAUSED;
	bool starting = c->base < 0 && c->code[c->cur & S3G_HIST_MASK] == 153;
	bool ending = c->base >= 0 && c->code[c->cur & S3G_HIST_MASK] == 154;
	if ((c->base < 0 && !starting) || (!running && !starting && !ending) || c->capacity == 0)
		goto unknown;
	/* a stable snapshot: the free space did not move around the stats */
	for (int tries = 0; tries < 50; tries++) {
		if ((*rc = s3g_get_buffer_free(s, &f1, err)) ||
		    (*rc = s3g_get_build_stats(s, &b, err)) ||
		    (*rc = s3g_get_buffer_free(s, &f2, err)))
			return S3G_LOST_RESEND;
		if (f1 == f2)
			break;
	}
	if (f1 != f2 || f1 > c->capacity)
		goto unknown;
	running = b.state == S3G_BUILD_RUNNING || b.state == S3G_BUILD_PAUSED;
	if (ending && !running) {
		/* the build end ran: the build is finished, the buffer empty,
		 * and its last line count takes in every command after our
		 * build start, the build end included */
		if (b.state == S3G_BUILD_FINISHED && f1 == c->capacity &&
		    (size_t)b.line == c->cur - (size_t)c->base) {
			s->st.resolved++;
			return S3G_LOST_QUEUED;
		}
		goto unknown;
	}
	if (starting) {
		/* the build start itself: no line count yet, but with no build
		 * before ours, running means it ran, and the bytes queued say
		 * whether it waits in the buffer (the only packet not yet run) */
		uint64_t queued = c->capacity - f1;
		if (c->running_before)
			goto unknown;
		if ((running && queued == 0) || (!running && queued == c->len[c->cur & S3G_HIST_MASK])) {
			s->st.resolved++;
			return S3G_LOST_QUEUED;
		}
		if (!running && queued == 0) {
			s->st.resolved++;
			return S3G_LOST_RESEND;
		}
		goto unknown;
	}
	{
		size_t first = (size_t)c->base + 1 + b.line; /* first command still queued */
		uint64_t queued = c->capacity - f1, without = 0;
		if (first == c->cur + 1) { /* already taken out and counted */
			s->st.resolved++;
			return S3G_LOST_QUEUED;
		}
		if (first > c->cur + 1 || c->cur - first >= S3G_STREAM_HISTORY)
			goto unknown;
		for (size_t i = first; i < c->cur; i++)
			without += c->len[i & S3G_HIST_MASK];
		if (queued == without + c->len[c->cur & S3G_HIST_MASK]) {
			s->st.resolved++;
			return S3G_LOST_QUEUED;
		}
		if (queued == without) {
			s->st.resolved++;
			return S3G_LOST_RESEND;
		}
	}
unknown:
	s->st.dup_risk++;
	return S3G_LOST_RESEND;
}

/* Refresh temperatures for the status, then call the progress callback. */
static void s3g_report(struct s3g *s, double t0, s3g_progress_fn progress, void *ctx)
{
	s->st.elapsed_s = s3g_now() - t0;
	if (progress)
		progress(ctx, &s->st);
}

/* ST_ERR_ARG unless k is one whole action command of at most 32 bytes. */
static int s3g_check_cmd(const struct s3g_cmd *k, size_t i, struct st_error *err)
{
	int want = k->payload && k->len ? s3g_action_length(k->payload, k->len) : -1;
	if (!k->payload || k->len == 0 || k->len > S3G_MAX_PAYLOAD || want != k->len)
		return st_error_set(err, ST_ERR_ARG,
				    "S3G stream command %zu (code %u, %u bytes) is not one "
				    "whole action command of at most %d bytes",
				    i, k->payload && k->len ? k->payload[0] : 0u, k->len,
				    S3G_MAX_PAYLOAD);
	return 0;
}

/* Wait until the packet of len bytes fits the printer's buffer: only poll
 * while it cannot.  Returns 0 (also when *stop was set: status says so) or
 * an error. */
static int s3g_wait_room(struct s3g *s, struct s3g_stream_ctx *c, uint32_t *free_est,
			 uint8_t len, double t0, double *next_report, s3g_progress_fn progress,
			 void *ctx, volatile sig_atomic_t *stop, struct st_error *err)
{
	double now = s3g_now(), idle_since = now;
	uint32_t seen = *free_est;
	struct s3g_temps temps;
	char last[160];
	int rc;

	while (*free_est < len) {
		if (stop && *stop) {
			s->st.interrupted = true;
			return 0;
		}
		s3g_sleep_ms(s->o.poll_ms);
		if ((rc = s3g_get_buffer_free(s, free_est, err)))
			return rc;
		if (*free_est > c->capacity)
			c->capacity = *free_est;
		now = s3g_now();
		if (*free_est != seen) {
			seen = *free_est;
			idle_since = now;
		}
		if (now >= c->next_stats) {
			if ((rc = s3g_check_reset(s, c, NULL, err)))
				return rc;
			/* heating counts as progress: waits block the buffer */
			int before = s->st.tool_temp + s->st.platform_temp;
			if (s3g_get_temps(s, &temps, NULL) == 0 &&
			    temps.tool + temps.platform != before)
				idle_since = now;
		}
		if (progress && now >= *next_report) {
			s3g_report(s, t0, progress, ctx);
			*next_report = now + 0.1;
		}
		if ((now - idle_since) * 1000.0 > s->o.overflow_deadline_ms) {
			s3g_last_desc(c, last, sizeof(last));
			return s3g_why(s, S3G_FAIL_PRINTER,
				       st_error_set(err, ST_ERR_IO,
						    "the printer's command buffer stayed full for %d "
						    "ms with no progress %s",
						    s->o.overflow_deadline_ms, last));
		}
	}
	return 0;
}

/* Poll until the printer is idle (or *stop). */
static int s3g_wait_done(struct s3g *s, struct s3g_stream_ctx *c, double t0, double *next_report,
			 s3g_progress_fn progress, void *ctx, volatile sig_atomic_t *stop,
			 struct st_error *err)
{
	struct s3g_temps temps;
	bool done = false;
	int rc;

	while (!done) {
		if (stop && *stop) {
			s->st.interrupted = true;
			break;
		}
		if ((rc = s3g_is_finished(s, &done, err)))
			return rc;
		double now = s3g_now();
		if (now >= c->next_stats || done) {
			if ((rc = s3g_check_reset(s, c, NULL, err)))
				return rc;
			s3g_get_temps(s, &temps, NULL);
		}
		if (progress && now >= *next_report) {
			s3g_report(s, t0, progress, ctx);
			*next_report = now + 0.1;
		}
		if (!done)
			s3g_sleep_ms(20);
	}
	return 0;
}

int s3g_stream_pull(struct s3g *s, s3g_source_fn next, void *src, size_t total,
		    s3g_progress_fn progress, void *ctx, volatile sig_atomic_t *stop,
		    struct s3g_status *st, struct st_error *err)
{
	struct s3g_stream_ctx *c;
	struct s3g_resolver res;
	uint8_t resp[S3G_MAX_PAYLOAD];
	size_t rlen;
	uint32_t free_est = 0;
	double t0 = s3g_now(), next_report = t0;
	struct s3g_temps temps;
	char last[160];
	int rc = 0;

	if (!s || !next)
		return st_error_set(err, ST_ERR_ARG, "s3g_stream: NULL argument");
	c = calloc(1, sizeof(*c));
	if (!c)
		return st_error_set(err, ST_ERR_NOMEM, "S3G stream: out of memory");
	c->n = total;
	c->base = -1;
	res = (struct s3g_resolver){s3g_decide, c};
	s->st.total = total;
	s->st.confirmed = s->st.skipped = 0;
	s->st.interrupted = false;
	s->st.fail = S3G_FAIL_NONE;
	if ((rc = s3g_get_buffer_free(s, &free_est, err)))
		goto out;
	c->capacity = free_est;
	{
		struct s3g_build_stats b0;
		if ((rc = s3g_check_reset(s, c, &b0, err)))
			goto out;
		c->running_before = b0.state == S3G_BUILD_RUNNING || b0.state == S3G_BUILD_PAUSED;
	}
	for (c->cur = 0;; c->cur++) {
		struct s3g_cmd k;
		double now = s3g_now();
		if (stop && *stop) {
			s->st.interrupted = true;
			break;
		}
		rc = next(src, &k, err);
		if (rc == 0)
			break;
		if (rc > 0)
			rc = s3g_check_cmd(&k, c->cur, err);
		if (rc < 0) {
			s->st.fail = S3G_FAIL_SOURCE;
			goto out;
		}
		c->len[c->cur & S3G_HIST_MASK] = k.len;
		c->code[c->cur & S3G_HIST_MASK] = k.payload[0];
		if (c->stats_due || now >= c->next_stats) {
			if ((rc = s3g_check_reset(s, c, NULL, err)))
				goto out;
			s3g_get_temps(s, &temps, NULL);
		}
		if (progress && now >= next_report) {
			s3g_report(s, t0, progress, ctx);
			next_report = now + 0.1;
		}
		rc = s3g_wait_room(s, c, &free_est, k.len, t0, &next_report, progress, ctx, stop,
				   err);
		if (rc || s->st.interrupted)
			goto out;
		uint64_t lost = s->st.timeouts + s->st.garbled, overflows = s->st.overflows;
		rc = s3g_send(s, k.payload, k.len, resp, sizeof(resp), &rlen, &res, err);
		if (rc < 0) {
			char inner[256];
			snprintf(inner, sizeof(inner), "%s", err ? err->msg : "");
			s3g_last_desc(c, last, sizeof(last));
			st_error_set(err, rc, "%s (%s)", inner, last);
			goto out;
		}
		if (s->st.timeouts + s->st.garbled != lost)
			c->stats_due = true;
		if (s->st.overflows != overflows || rc == 1)
			free_est = 0; /* our count was off: ask again before the next */
		else if (free_est >= k.len)
			free_est -= k.len;
		if (rc == 0 && resp[0] == S3G_RC_UNSUPPORTED) {
			s->st.skipped++;
		} else {
			s->st.confirmed++;
			s->st.action_bytes += k.len;
			if (k.payload[0] == 153) {
				c->base = (long)c->cur;
				c->seen_running = false;
				c->last_line = 0;
			}
		}
		rc = 0;
	}
	if (!s->st.interrupted && s->o.wait_finished)
		rc = s3g_wait_done(s, c, t0, &next_report, progress, ctx, stop, err);
out:
	if (rc < 0 && err && !strstr(err->msg, "confirmed")) {
		char inner[256];
		snprintf(inner, sizeof(inner), "%s", err->msg);
		s3g_last_desc(c, last, sizeof(last));
		st_error_set(err, rc, "%s (%s)", inner, last);
	}
	free(c);
	s->st.elapsed_s = s3g_now() - t0;
	if (progress)
		progress(ctx, &s->st);
	if (st)
		*st = s->st;
	return rc;
}

/* The source over an array, for s3g_stream. */
struct s3g_array_src {
	const struct s3g_cmd *cmds;
	size_t n, next;
};

static int s3g_array_next(void *src, struct s3g_cmd *cmd, struct st_error *err)
{
	struct s3g_array_src *a = src;
	(void)err;
	if (a->next >= a->n)
		return 0;
	*cmd = a->cmds[a->next++];
	return 1;
}

int s3g_stream(struct s3g *s, const struct s3g_cmd *cmds, size_t n, s3g_progress_fn progress,
	       void *ctx, volatile sig_atomic_t *stop, struct s3g_status *st,
	       struct st_error *err)
{
	struct s3g_array_src a = {cmds, n, 0};
	int rc;

	if (!s || (!cmds && n))
		return st_error_set(err, ST_ERR_ARG, "s3g_stream: NULL argument");
	/* all checked before the first packet: a bad array sends nothing */
	for (size_t i = 0; i < n; i++)
		if ((rc = s3g_check_cmd(&cmds[i], i, err)))
			return rc;
	return s3g_stream_pull(s, s3g_array_next, &a, n, progress, ctx, stop, st, err);
}
