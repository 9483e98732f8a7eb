/*
 * marlin_connect.c - the handshake: M110 N0 and M115 until both are
 * answered, capabilities, auto-reported temperatures (docs/streaming.md,
 * docs/protocols.md section 1).
 */
#include <stdio.h>
#include <string.h>

#include "marlin_impl.h"

/* Handle replies until the line has been quiet for quiet_ms (at most
 * max_ms in all). */
static int marlin_wait_quiet(struct marlin *m, int quiet_ms, int max_ms, struct st_error *err)
{
	double end = marlin_now_s(m) + max_ms / 1000.0;
	while (marlin_now_s(m) < end) {
		int rc = marlin_read(m, quiet_ms, err);
		if (rc <= 0)
			return rc;
	}
	return 0;
}

int marlin_connect(struct marlin *m, struct st_error *err)
{
	double t0 = marlin_now_s(m), end = t0 + m->o.connect_timeout_ms / 1000.0;
	char buf[2 * MARLIN_LINE_CAP + 2];
	int rc;

	m->connected = false;
	if (m->o.expect_reset) {
		/* The bootloader must see no bytes: wait for the banner, then
		 * for the rest of it. */
		double boot_end = t0 + m->o.boot_wait_ms / 1000.0;
		while (marlin_now_s(m) < boot_end) {
			double last = m->t_rx;
			rc = marlin_read(m, 100, err);
			if (rc < 0)
				return rc;
			if (rc == 0 && last > t0)
				break; /* something came, then 100 ms of quiet */
		}
	}
	for (int attempt = 0; marlin_now_s(m) < end; attempt++) {
		int k = 0;
		buf[k++] = '\n'; /* ends any fragment left in the firmware's line */
		rc = gcode_format_numbered(buf + k, sizeof(buf) - (size_t)k - 2, 0, "M110 N0");
		if (rc <= 0)
			return st_error_set(err, ST_ERR_INTERNAL, "cannot format M110");
		k += rc;
		buf[k++] = '\n';
		rc = gcode_format_numbered(buf + k, sizeof(buf) - (size_t)k - 2, 1, "M115");
		if (rc <= 0)
			return st_error_set(err, ST_ERR_INTERNAL, "cannot format M115");
		k += rc;
		buf[k++] = '\n';
		marlin_trace(m, ">", buf + 1, (size_t)k - 1);
		if ((rc = marlin_write(m, buf, (size_t)k, err)))
			return rc;
		/* Answer: ok (M110), FIRMWARE_NAME, Cap lines, ok (M115); some
		 * boards and serial bridges answer M115 with a bare ok, and
		 * then the capabilities stay unknown. */
		bool fw = false, done = false, out_of_step = false;
		int oks = 0;
		double t_written = marlin_now_s(m), first_ok_s = 0;
		double until = marlin_now_s(m) + m->o.retry_ms / 1000.0;
		if (until > end)
			until = end;
		while (!done && marlin_now_s(m) < until) {
			double left = until - marlin_now_s(m);
			char b[1024];
			struct st_error e = {0};
			int n = xport_read(m->x, b, sizeof(b), (int)(left * 1000.0) + 1, &e);
			if (n < 0)
				return st_error_set(err, ST_ERR_IO, "%s: %s", xport_describe(m->x),
						    e.msg);
			double now = marlin_now_s(m);
			if (n > 0)
				m->t_rx = now;
			for (int i = 0; i < n && !done; i++) {
				char c = b[i];
				if (c != '\n' && c != '\r') {
					if (m->rx_len < MARLIN_RX_MAX)
						m->rx[m->rx_len++] = c;
					continue;
				}
				if (!m->rx_len)
					continue;
				struct marlin_reply r;
				char text[MARLIN_RX_MAX + 1];
				size_t tl = m->rx_len;
				memcpy(text, m->rx, tl);
				text[tl] = '\0';
				m->rx_len = 0;
				marlin_trace(m, "<", text, tl);
				enum marlin_reply_kind kind =
					marlin_parse_reply(text, tl, &r, &m->st, &m->caps);
				if (kind == MARLIN_REPLY_FIRMWARE) {
					fw = true;
				} else if (kind == MARLIN_REPLY_OK && !out_of_step) {
					marlin_learn_b(m, &r);
					if (!oks && !fw)
						first_ok_s = now - t_written; /* M110's */
					done = fw || ++oks == 2;
				} else if (kind == MARLIN_REPLY_FATAL) {
					return st_error_set(err, ST_ERR_INTERNAL,
							    "the printer on %s reports a fatal error: "
							    "\"%.100s\"; fix it and reset the printer",
							    xport_describe(m->x), text);
				} else if (kind == MARLIN_REPLY_RESEND ||
					   kind == MARLIN_REPLY_LINE_ERROR) {
					/* one of our two lines was spoilt: the "ok"
					 * after the Resend is the error's, not an
					 * answer (a bare-ok M115 would look answered
					 * while the firmware still counts from N0) */
					out_of_step = true;
					until = now;
				}
				/* "start" may be an old banner still in the pipe:
				 * let the attempt be answered or time out. */
			}
		}
		if (!done) {
			/* let the rest of a spoilt attempt's answer go by,
			 * or it is taken for the next attempt's */
			if (out_of_step && (rc = marlin_wait_quiet(m, 200, m->o.retry_ms, err)))
				return rc;
			continue;
		}
		/* Answers to an earlier attempt may follow; they must not count
		 * as acks, and if one of them reset the line numbers (an M110
		 * read after our M115), start over.  Two bare oks may also be
		 * an old ok and our M110's: an ok more after them means so. */
		if (attempt > 0 || !fw) {
			uint64_t seen = m->st.resend_requests, strays = m->st.stray_oks;
			if ((rc = marlin_wait_quiet(m, 200, m->o.retry_ms, err)))
				return rc;
			if (m->st.resend_requests != seen || (!fw && m->st.stray_oks != strays))
				continue;
		}
		m->st.resend_requests = 0;
		m->skip_ok = 0;
		m->st.stray_oks = 0;
		m->n_next = m->n_send = 2;
		m->n_acked = m->n_max_sent = m->last_tx_n = 1;
		m->n_acked_hi = m->n_taken = 1;
		m->probed = false;
		m->m105_n = m->phantom_n = m->phantom_bytes = m->m105_gone_bytes = m->m105_late = 0;
		m->m105_spent = false;
		m->t_busy = 0;
		marlin_hist_entry(m, 0)->n = 0;
		marlin_hist_entry(m, 1)->n = 0; /* not resendable: connect lines are not kept */
		m->connected = true;
		/* the round trip of M110 is the first sample: without one the
		 * first lost ok would wait the whole probe_ms (an earlier
		 * attempt's ok may make it short: a probe that comes early
		 * only waits in the ring, and later samples correct it) */
		if (first_ok_s > 0)
			m->rtt = first_ok_s;
		m->t_rx = m->t_progress = marlin_now_s(m);
		if (m->caps.autoreport_temp && m->o.autoreport_s > 0) {
			char cmd[32];
			snprintf(cmd, sizeof(cmd), "M155 S%d", m->o.autoreport_s);
			marlin_push_prio(m, cmd);
			while (!marlin_idle(m)) {
				if (marlin_now_s(m) > end)
					return st_error_set(err, ST_ERR_IO,
							    "the printer on %s did not acknowledge "
							    "M155 within %d s",
							    xport_describe(m->x),
							    m->o.connect_timeout_ms / 1000);
				if ((rc = marlin_step(m, 50, err)))
					return rc;
			}
		}
		return 0;
	}
	return st_error_set(err, ST_ERR_IO,
			    "no answer from a Marlin printer on %s within %d s; check that it is "
			    "switched on and that the baud rate matches its firmware",
			    xport_describe(m->x), m->o.connect_timeout_ms / 1000);
}
