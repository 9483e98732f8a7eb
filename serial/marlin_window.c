/*
 * marlin_window.c - how many lines may be in flight (the firmware's RX
 * ring and command queue), acknowledgements, Resend rewinds and probes
 * (docs/streaming.md "The window").
 */

#include <string.h>

#include "marlin_impl.h"

/* The oldest awaited probe is no longer awaited. */
static void m105_pop(struct marlin *m)
{
	memmove(m->m105, m->m105 + 1, --m->m105_n * sizeof(m->m105[0]));
}

static void ghost_clear(struct marlin *m)
{
	m->ghost_head = m->ghost_n = m->ghost_bytes = 0;
	m->stale_left = 0;
	m->rewinding = false;
}

static void ghost_push(struct marlin *m, uint16_t len)
{
	if (m->ghost_n == MARLIN_MAX_INFLIGHT)
		return;
	m->ghost[(m->ghost_head + m->ghost_n++) % MARLIN_MAX_INFLIGHT] = len;
	m->ghost_bytes += len;
}

static void ghost_pop(struct marlin *m)
{
	if (!m->ghost_n)
		return;
	m->ghost_bytes -= m->ghost[m->ghost_head];
	m->ghost_head = (m->ghost_head + 1) % MARLIN_MAX_INFLIGHT;
	m->ghost_n--;
}

/*
 * Lines in flight that are surely out of the RX ring (0 = unknown).
 * Marlin reads its ring only in its main loop, between commands: lines
 * that arrive while a command waits (a move for a planner block) stay in
 * the ring even with queue slots free.  ADVANCED_OK's "ok N<n> B<b>" says
 * how many commands besides n were queued when n finished (largest B
 * seen, BUFSIZE - 1, minus b): those, and no more, are out of the ring
 * (docs/streaming.md "The window").  A declared bufsize without
 * ADVANCED_OK counts BUFSIZE - 1, the running command's slot aside.
 */
static unsigned marlin_slots(const struct marlin *m)
{
	if (m->caps.advanced_ok)
		return (unsigned)m->queued;
	return m->o.bufsize ? m->o.bufsize - 1 : 0;
}

/* An ADVANCED_OK B<b>: learn BUFSIZE - 1. */
void marlin_learn_b(struct marlin *m, const struct marlin_reply *r)
{
	if (r->has_n || r->has_b)
		m->caps.advanced_ok = true;
	if (r->has_b && r->b < 4096 && (unsigned)r->b > m->bufsize_learnt)
		m->bufsize_learnt = (unsigned)r->b;
}

/*
 * May a line of len bytes go out now?  The oldest `slots` lines in flight
 * have left the RX ring for the command queue (Marlin reads the ring only
 * while a slot is free, and answers "ok" only when the command is done);
 * the rest, plus copies written before a rewind, must fit in the ring.
 */
/* Bytes in the RX ring as far as we count: lines in flight but the
 * oldest `slots`, copies from before a rewind, and the unnumbered lines
 * (probes, emergency lines) not yet answered: while a command blocks
 * (M190), they wait in the ring like any line. */
static size_t marlin_ring_bytes(const struct marlin *m, unsigned slots)
{
	size_t bytes = m->ghost_bytes + m->phantom_bytes + m->m105_gone_bytes +
		       m->m105_n * (sizeof(MARLIN_M105_PROBE) - 1);
	/* lines the firmware said it has (Resend) left the ring as well */
	long first = m->n_acked + 1 + (long)slots;
	if (first <= m->n_taken)
		first = m->n_taken + 1;
	for (long n = first; n < m->n_send; n++)
		bytes += m->hist[(unsigned long)n % MARLIN_HIST].len;
	return bytes;
}

bool marlin_window_open(const struct marlin *m, size_t len)
{
	long inflight = m->n_send - 1 - m->n_acked;
	unsigned slots = marlin_slots(m);
	size_t bytes;

	if (inflight <= 0)
		return true; /* one in flight always */
	if (inflight >= MARLIN_MAX_INFLIGHT || inflight >= (long)m->cwnd)
		return false;
	if (!m->o.rx_buffer)
		return slots && (unsigned long)inflight < slots;
	bytes = marlin_ring_bytes(m, slots);
	if ((unsigned long)inflight >= slots)
		bytes += len;
	/* AVR rings hold size - 1 bytes; room is kept for the M105 probe,
	 * which must fit even when lost oks make the ring look full */
	return bytes + 1 + sizeof(MARLIN_M105_PROBE) - 1 <= m->o.rx_buffer;
}

/* Account lines (n_acked, n] as acknowledged. */
void marlin_ack_through(struct marlin *m, long n)
{
	struct marlin_entry *last = marlin_hist_entry(m, n);
	if (last->n == n && last->t_sent > 0 && !last->blocking) {
		double sample = marlin_now_s(m) - last->t_sent;
		m->rtt = m->rtt > 0 ? 0.875 * m->rtt + 0.125 * sample : sample;
	}
	for (long k = m->n_acked + 1; k <= n; k++) {
		struct marlin_entry *e = marlin_hist_entry(m, k);
		if (e->n != k || !e->job)
			continue;
		m->st.acked++;
		m->st.bytes_acked += e->len;
		m->st.last_acked_n = k;
		m->st.last_acked_src = e->src;
		m->st.layer = e->layer;
		m->st.z = e->z;
	}
	/* unnumbered lines written before line n ran before it: their
	 * answers, if still missing, were lost, and they left the ring */
	while (m->m105_n && m->m105[0].after < n)
		m105_pop(m);
	if (m->m105_gone_after < n)
		m->m105_gone_bytes = 0;
	while (m->phantom_n && m->phantom[0].after < n)
		marlin_phantom_pop(m);
	m->queued = m->queued > n - m->n_acked ? m->queued - (n - m->n_acked) : 0;
	m->cwnd += (double)(n - m->n_acked);
	if (m->cwnd > MARLIN_MAX_INFLIGHT)
		m->cwnd = MARLIN_MAX_INFLIGHT;
	m->n_acked = n;
	m->m105_spent = false;
	if (n > m->n_acked_hi)
		m->n_acked_hi = n;
	if (m->n_send <= n)
		m->n_send = n + 1;
	if (m->rewinding && n >= m->rewind_k)
		ghost_clear(m); /* a copy after the rewind got through: the old ones are gone */
}

void marlin_phantom_push(struct marlin *m, size_t len)
{
	if (m->phantom_n == MARLIN_PHANTOMS)
		marlin_phantom_pop(m); /* the oldest surely ran long ago */
	m->phantom[m->phantom_n++] = (struct marlin_phantom){m->last_tx_n, (uint16_t)len};
	m->phantom_bytes += len;
}

void marlin_phantom_pop(struct marlin *m)
{
	if (!m->phantom_n)
		return;
	m->phantom_bytes -= m->phantom[0].len;
	memmove(m->phantom, m->phantom + 1, --m->phantom_n * sizeof(m->phantom[0]));
}

/* Undo the accounting of lines (n, n_acked]: the firmware says it never
 * took them (an "ok" we counted belonged to something else). */
static void marlin_unack_to(struct marlin *m, long n)
{
	for (long k = n + 1; k <= m->n_acked; k++) {
		struct marlin_entry *e = marlin_hist_entry(m, k);
		if (e->n != k || !e->job || !m->st.acked)
			continue;
		m->st.acked--;
		m->st.bytes_acked -= e->len;
	}
	m->n_acked = n;
	m->queued = 0;
}

/*
 * The firmware says it has every line up to `have` (a "Resend: have + 1")
 * while we count fewer acknowledged: it is ahead of us.  Lines we had seen
 * acknowledged before an un-ack (a late Resend taken for a new one) are
 * done again.  The others it has taken, not run: they may wait in its
 * command queue, their oks to come (after a stall Marlin reads its ring
 * before it runs the next command), so they leave the RX ring's count
 * and nothing more.  Counting them as run made the oks that followed
 * count for later lines, and a job ended before its last lines ran
 * (marlin: stall_before_last_lines).  Oks lost meanwhile are settled by
 * the next M105 probe, whose answer comes only after they ran.
 */
static void marlin_firmware_has(struct marlin *m, long have)
{
	m->m105_spent = false; /* an M105 probe may now vouch for `have` */
	if (have > m->n_acked) {
		long done = m->n_acked_hi > have ? have : m->n_acked_hi;
		if (done > m->n_acked) {
			marlin_hist_entry(m, done)->t_sent = 0; /* no round-trip sample */
			marlin_ack_through(m, done);
		}
	}
	m->n_taken = have;
}

/* "Resend: k": the firmware has taken every line before k, none after. */
int marlin_resend(struct marlin *m, long k, struct st_error *err)
{
	char where[160];
	if (k < 1 || k > m->n_max_sent + 1 || marlin_hist_entry(m, k)->n != k || k < m->n_acked - 8) {
		if (k == m->n_max_sent + 1 && k == m->n_next) {
			/* the next line, never written: nothing to rewind */
			ghost_clear(m);
			marlin_firmware_has(m, k - 1);
			return 0;
		}
		marlin_where(m, where, sizeof(where));
		return marlin_fail(m, MARLIN_FAIL_LINK, err,
				   "the printer asked for line N%ld again, which this job %s "
				   "(was the printer reset?); %s",
				   k, k > m->n_max_sent ? "never sent" : "no longer keeps", where);
	}
	m->m105_spent = false;
	if (m->rewinding && k == m->rewind_k && m->stale_left > 0) {
		/* caused by a copy written before our rewind: already handled */
		m->stale_left--;
		ghost_pop(m);
		return 0;
	}
	ghost_clear(m);
	/* Go-back-N: every line after a spoilt one is written again, so
	 * while errors are frequent a smaller window wastes fewer copies
	 * (at 4 % of bytes hit, 12 writes a line at full window) */
	m->cwnd = m->cwnd / 2 < 1 ? 1 : m->cwnd / 2;
	if (k - 1 < m->n_acked)
		marlin_unack_to(m, k - 1);
	marlin_firmware_has(m, k - 1);
	for (long n = k; n < m->n_send; n++)
		ghost_push(m, marlin_hist_entry(m, n)->len);
	m->stale_left = m->ghost_n ? m->ghost_n - 1 : 0;
	ghost_pop(m); /* the copy that caused this request has been read */
	m->rewinding = true;
	m->rewind_k = k;
	m->n_send = k;
	return 0;
}

/* Is a blocking command (G28, M109, M400 ...) among the lines in flight?
 * During a rewind only the lines before the one asked for again: the
 * firmware said it has none of the others, so none of them runs (a
 * flushed M400 would make its temperature reports look like progress and
 * the job wait for ever). */
bool marlin_blocking_inflight(const struct marlin *m)
{
	long hi = m->n_max_sent < m->n_next ? m->n_max_sent : m->n_next - 1;
	if (m->rewinding && hi >= m->rewind_k)
		hi = m->rewind_k - 1;
	for (long n = m->n_acked + 1; n <= hi; n++)
		if (m->hist[(unsigned long)n % MARLIN_HIST].blocking)
			return true;
	return false;
}

/* Is an M105 of the job among the lines in flight?  Its answer is an
 * "ok T:" like a probe's. */
static bool marlin_job_m105_inflight(struct marlin *m)
{
	for (long n = m->n_acked + 1; n < m->n_send; n++) {
		const struct marlin_entry *e = marlin_hist_entry(m, n);
		if (e->n == n && strstr(e->text, "M105"))
			return true;
	}
	return false;
}

/*
 * Marlin echoes a command it does not know, quoted ("echo:Unknown command:
 * \"117\""), then answers it "ok".  A line of the job it does not know
 * (M862.3 on another firmware) is in flight with that text.  Anything else
 * is a fragment of a damaged line run without a number, most often a
 * checksum's digits after its '*' turned into a newline: its ok is no
 * line's, and counted for one it ended a job a line early (marlin:
 * fragment_ok).  A fragment that is a probe with one byte spoilt will
 * never be answered "ok T:": it ran, so every probe before it had its
 * turn, and the oldest awaited is it.
 */
bool marlin_unknown_fragment(struct marlin *m, const char *line, size_t len)
{
	const char *q = memchr(line, '"', len), *end = line + len;
	while (end > line && end[-1] != '"')
		end--;
	if (!q || end - 1 <= q)
		return false; /* nothing quoted: cannot tell, count it as before */
	q++;
	size_t qlen = (size_t)(end - 1 - q);
	for (long n = m->n_acked + 1; n < m->n_send; n++) {
		const struct marlin_entry *e = marlin_hist_entry(m, n);
		const char *c = e->n == n ? memchr(e->text, ' ', e->len) : NULL;
		const char *star = c ? memchr(c, '*', e->len - (size_t)(c - e->text)) : NULL;
		if (star && (size_t)(star - c - 1) == qlen && !memcmp(c + 1, q, qlen))
			return false;
	}
	int diff = 0;
	for (size_t i = 0; qlen == 4 && i < 4; i++)
		diff += q[i] != "M105"[i];
	if (m->m105_n && diff == 1)
		m105_pop(m);
	return true;
}

/* The counters an M105 probe's answer must find unchanged. */
static uint64_t marlin_marks(const struct marlin *m)
{
	return m->st.resend_requests + m->st.line_errors + m->st.other_errors +
	       m->st.unknown_commands;
}

/*
 * Is the oldest probe's answer no longer to be expected?  Without a
 * blocking command in flight, after probe_ms.  With one (G28, M190), or
 * once the firmware reported busy since the probe (a command we cannot
 * see as long holds its queue), the probe waits in the ring behind it,
 * its answer still to come while the firmware reports busy or heating:
 * only a silence of probe_ms (at least MARLIN_BUSY_HOLD_S) since the
 * probe or the last such report gives it up.
 */
static bool marlin_m105_overdue(const struct marlin *m, double now)
{
	double probe_s = m->o.probe_ms / 1000.0, since = m->m105[0].t;
	if (!marlin_blocking_inflight(m) && m->t_busy <= since)
		return now - since > probe_s;
	if (m->t_busy > since)
		since = m->t_busy;
	return now - since > (probe_s > MARLIN_BUSY_HOLD_S ? probe_s : MARLIN_BUSY_HOLD_S);
}

/*
 * May an M105 probe go out now?  Not while one written less than
 * MARLIN_M105_AGAIN_S ago waits for its answer, nor with a numbered
 * M105 in flight (its "ok T:" would be taken for the probe's), nor while
 * the firmware reports that it is busy or heating (it is alive, and
 * probes would pile up in its ring), nor when one might not fit in the
 * RX ring, nor with MARLIN_M105_MAX waiting.  Overdue probes are given
 * up (their answers were lost); the answers still to come then cannot be
 * told apart, and acknowledge nothing.
 */
static bool marlin_m105_may(struct marlin *m, double now)
{
	const size_t len = sizeof(MARLIN_M105_PROBE) - 1;
	while (m->m105_n && marlin_m105_overdue(m, now)) {
		/* a stalled board still holds it: its bytes count in the
		 * ring until a line written after it is acknowledged */
		m->m105_gone_bytes += len;
		m->m105_gone_after = m->m105[0].after;
		m105_pop(m);
		for (size_t i = 0; i < m->m105_n; i++)
			m->m105[i].valid = false;
	}
	if (m->m105_late && now - m->t_m105_late < m->o.probe_ms / 1000.0)
		return false;
	m->m105_late = 0; /* those answers were lost */
	if (m->m105_spent || m->m105_n == MARLIN_M105_MAX ||
	    (m->m105_n && now - m->m105[m->m105_n - 1].t < MARLIN_M105_AGAIN_S))
		return false;
	if (m->t_busy > 0 && now - m->t_busy < MARLIN_BUSY_HOLD_S)
		return false;
	if (marlin_job_m105_inflight(m))
		return false;
	return !m->o.rx_buffer || marlin_ring_bytes(m, marlin_slots(m)) + len + 1 <= m->o.rx_buffer;
}

/*
 * A probe is going out: an ok that comes after it may be the answer to
 * the probe's newline (the line's own was lost) rather than to the line,
 * so no line in flight gives a round-trip sample (Karn's rule).  One such
 * sample of seconds would stretch the silence before every later probe
 * and rewrite for dozens of lines.
 */
static void marlin_unsample_inflight(struct marlin *m)
{
	for (long n = m->n_acked + 1; n < m->n_send; n++)
		marlin_hist_entry(m, n)->t_sent = 0;
}

/* Write an M105 probe ("\n" first ends a fragment whose newline was lost). */
static int marlin_m105_write(struct marlin *m, double now, struct st_error *err)
{
	marlin_unsample_inflight(m);
	m->m105[m->m105_n++] = (struct marlin_m105){m->n_send - 1, marlin_marks(m), now, true,
						    m->n_taken >= m->n_send - 1};
	marlin_trace(m, ">", "M105", 4);
	return marlin_write(m, MARLIN_M105_PROBE, sizeof(MARLIN_M105_PROBE) - 1, err);
}

/*
 * An "ok T:" with probes outstanding is the oldest one's answer (or, if
 * that one's was lost, a later one's: it then says at least as much).
 * Marlin runs its queue in order and answers M105 when it runs it, so
 * every line written before the probe has run -- unless an error, a
 * Resend or an unknown command (a line spoilt past its number) came since.
 */
bool marlin_m105_answer(struct marlin *m)
{
	if (!m->m105_n) {
		/* No probe awaited: unless an M105 of the job is in flight,
		 * this answers one given up as overdue, and acknowledges
		 * nothing.  Taken for a line's ok, each such answer ended a
		 * job a line early (marlin: long_busy_late_answers). */
		if (m->m105_late)
			m->m105_late--;
		else if (marlin_job_m105_inflight(m))
			return false;
		m->st.stray_oks++;
		return true;
	}
	struct marlin_m105 e = m->m105[0];
	m105_pop(m);
	/* Not the last line before it, unless the firmware had said it has
	 * it: a copy of it whose number noise turned into the one before was
	 * dropped silently as a duplicate (queue.cpp drops last_N - 1 and
	 * last_N), and only a line after it would have drawn a Resend.  The
	 * older probe then asks where the firmware is. */
	long upto = e.after_taken ? e.after : e.after - 1;
	if (e.valid && e.marks == marlin_marks(m) && upto > m->n_acked && upto < m->n_next &&
	    upto <= m->n_max_sent) {
		marlin_hist_entry(m, upto)->t_sent = 0; /* no round-trip sample */
		marlin_ack_through(m, upto);
	} else {
		/* an answer older than the later probes' says no less than
		 * theirs: with one line in flight, each probe answered in
		 * turn would vouch for nothing for ever */
		m->m105_spent = true;
		/* Which probe it answered is not known once one's answer was
		 * lost (noise on an "ok T:"): counted for the one before it,
		 * every later answer was, for ever, as a new probe went out
		 * before the last one's answer came (marlin: lost_oks, a
		 * livelock).  The others are no longer awaited, and no probe
		 * goes out while their answers may still come. */
		m->m105_late = m->m105_n;
		m->m105_n = 0;
		m->t_m105_late = marlin_now_s(m);
	}
	return true;
}

/*
 * Nothing answered for a while.  Without a rewind the first resort is
 * the M105 probe above: lost oks are then counted within a few round
 * trips, and it is harmless when the firmware is only slow (a long move,
 * a G28): it waits in the ring.  Otherwise, after probe_ms and with no
 * blocking command in flight, the older probe.  Silence may be a stall (a busy host
 * computer, a board held up) with every copy in flight still in the RX
 * ring: rewrites behind them would overflow it (the fragments would run)
 * and reach the firmware as old line numbers, each an error that empties
 * the ring under the lines that follow, each error's Resend a new rewind.
 * So a probe rewrites nothing.  The first ends a fragment whose end was
 * lost ("\n": the firmware then asks for the line).  Unanswered ones
 * (the 2nd, 4th, 8th ...) add a copy of a line the firmware surely has
 * and that is not one of its last two (those it drops silently): its
 * answer is always "Resend: last + 1", which says where it is, be it
 * ahead (lost oks), behind (lost lines) or just back from a stall.  After
 * a rewind the silence means flushed copies: rewrite from the first line
 * it has not reported having.
 */
int marlin_probe(struct marlin *m, double now, bool blocking, struct st_error *err)
{
	bool rewinding = m->rewinding;
	if (!rewinding && marlin_m105_may(m, now))
		return marlin_m105_write(m, now, err);
	/* A probe was answered and vouched for nothing new: the firmware is
	 * idle and lacks our last line (eaten as a fragment, or dropped as a
	 * duplicate).  Ask where it is at once. */
	bool ask = !rewinding && m->m105_spent && !blocking;
	if (!rewinding && !ask && (blocking || now - m->t_progress <= m->o.probe_ms / 1000.0))
		return 0;
	if (!m->probed)
		m->silent_probes = 0; /* something answered since the last probe */
	marlin_unsample_inflight(m);
	m->t_progress = now;
	m->probed = true;
	if (rewinding) {
		long from = (m->n_taken > m->n_acked ? m->n_taken : m->n_acked) + 1;
		ghost_clear(m);
		m->skip_ok = 0;
		m->n_send = from < m->n_send ? from : m->n_send;
		return marlin_write(m, "\n", 1, err);
	}
	unsigned k = m->silent_probes++;
	if (marlin_write(m, "\n", 1, err))
		return ST_ERR_IO;
	long n = m->n_acked - 2; /* below the two the firmware drops silently */
	struct marlin_entry *e = marlin_hist_entry(m, n);
	if ((!ask && (!k || (k & (k + 1)))) || n < 1 || e->n != n)
		return 0;
	marlin_trace(m, ">", e->text, e->len);
	m->st.resends++;
	return marlin_write(m, e->text, e->len, err);
}
