/*
 * s3g.h - the S3G packet layer and host driver for Makerbot-family printers
 * running Sailfish (FlashForge Creator Pro); docs/protocols.md section 2.
 *
 * Three layers, usable separately:
 *   1. Framing: 0xD5, length (<= 32), payload, CRC-8 (iButton/Maxim,
 *      reflected 0x8C, init 0) of the payload; a stateless framer that
 *      resynchronises on garbage.
 *   2. Tables: response codes with the host action each calls for, and the
 *      length of every action (buffered) command by code, as the firmware
 *      parses its command buffer.
 *   3. A driver over a struct xport: one packet out, one response back,
 *      with the retry policy below; the queries a host needs; a safe cancel;
 *      and a streaming loop that keeps the firmware's command buffer full
 *      without overflowing it.
 *
 * Retry policy (s3g protocol document "Handling Errors"; Sailfish Host.cc;
 * GPX gpx.c port_handler):
 *   0x81 success            -> next packet
 *   0x82 buffer overflow    -> the firmware discarded the packet: poll the
 *                              free space, resend the same packet when it
 *                              fits; unbounded, but a deadline without any
 *                              progress (free space or temperatures moving)
 *   0x80 generic, 0x83 CRC, 0x88 tool lock, 0x8C packet timeout, and 0x84
 *   for a packet we know is <= 32 bytes (line noise turned the length byte
 *   into something larger) -> drain stray replies, resend; bounded by
 *                              max_rejects, apart from the time-outs'
 *                              max_retries (a reply shows the link alive);
 *                              so are replies damaged on the way (bad CRC)
 *   0x85 unsupported        -> skip the command, count it
 *   0x87, 0x89 cancelled on the printer, 0x8A building from SD, 0x8B
 *   overheat                -> stop with an error naming the code
 *   no valid reply within the time-out -> see "exactly once" below.
 *
 * Exactly once.  S3G packets carry no sequence number, so a reply lost on
 * the way back leaves the host unsure whether the firmware queued the
 * packet.  Sailfish and GPX do nothing about it (GPX gives up on a
 * time-out; the s3g document just retries).  This driver resends queries
 * freely (they change nothing), and for an action packet inside
 * s3g_stream it first asks the firmware: the build statistics' line number
 * (commands taken out of the buffer since the build start notification)
 * and the free buffer space (read twice around it until stable) tell how
 * many bytes are still queued; the host knows the length of every command
 * it had confirmed, so the queued byte count matches either "packet queued"
 * or "packet not queued", and the packet is resent only in the second case.
 * The same check runs before resending after an error reply, because a
 * damaged packet makes the firmware answer each of its noise bytes with
 * 0x80, and a late one can be taken for the reply to the next copy.
 * The line number counts every action command Sailfish runs (Command.cc
 * LINE_NUMBER_INCR; the build start clears it, queries never count), so
 * a packet CRC-8 let through damaged, run as two commands or none, leaves
 * it off from the commands confirmed: after any fault the stream counts
 * again before the next packet (the bytes queued tell the first command
 * still queued, the line number against it the offset, status.drifts
 * counts the changes), so the offset is the one of a moment ago when a
 * reply is lost.  Where that cannot decide (no build start notification
 * in the stream, the reply to the damaged packet itself lost, or neither
 * count matches), the packet is resent as the protocol document says and
 * status.dup_risk counts it.  What a damaged packet that CRC-8 let
 * through runs is beyond any host's reach.
 *
 * Reset detection.  Sailfish sends nothing when it reboots; it simply
 * answers as freshly booted: build statistics state 0 ("no build
 * initialized (boot up state)"), line number 0, empty buffer.  s3g_stream
 * checks the build statistics once a second and after every time-out;
 * once the build was seen running, state 0 or a line number going
 * backwards is reported as a reset, naming the last confirmed packet.
 *
 * Library code: nothing is printed.  One driver per transport, used by one
 * thread at a time.
 */
#ifndef STRATUM_SERIAL_S3G_H
#define STRATUM_SERIAL_S3G_H

#include <signal.h>
#include <stdbool.h>
#include <stddef.h>
#include <stdint.h>

#include "st_error.h"
#include "xport.h"

#define S3G_START 0xD5		/* first byte of every packet */
#define S3G_MAX_PAYLOAD 32	/* Mightyboard MAX_PACKET_PAYLOAD (bytes) */
#define S3G_MAX_PACKET (S3G_MAX_PAYLOAD + 3)
#define S3G_BUFFER_SIZE 512	/* Sailfish COMMAND_BUFFER_SIZE (bytes) */
#define S3G_PACKET_TIMEOUT_MS 200 /* Sailfish HOST_PACKET_TIMEOUT_MS */

/* Response codes: payload byte 0 of every reply (Sailfish Packet.hh). */
enum s3g_rc {
	S3G_RC_GENERIC_ERROR = 0x80,
	S3G_RC_OK = 0x81,
	S3G_RC_BUFFER_OVERFLOW = 0x82,
	S3G_RC_CRC_MISMATCH = 0x83,
	S3G_RC_QUERY_TOO_BIG = 0x84,
	S3G_RC_UNSUPPORTED = 0x85,
	S3G_RC_EXPECT_MORE = 0x86,
	S3G_RC_DOWNSTREAM_TIMEOUT = 0x87,
	S3G_RC_TOOL_LOCK_TIMEOUT = 0x88,
	S3G_RC_CANCEL_BUILD = 0x89,
	S3G_RC_BOT_BUILDING = 0x8A,
	S3G_RC_BOT_OVERHEAT = 0x8B,
	S3G_RC_PACKET_TIMEOUT = 0x8C,
};

/* What the host does about a response code. */
enum s3g_action {
	S3G_ACT_NEXT,	     /* success: go on */
	S3G_ACT_RETRY,	     /* resend the same packet, bounded */
	S3G_ACT_WAIT_RESEND, /* wait for buffer room, resend; unbounded */
	S3G_ACT_SKIP,	     /* the firmware does not know it: skip, warn */
	S3G_ACT_FAIL,	     /* error: stop */
	S3G_ACT_STOP,	     /* the printer stopped the build: stop */
};

/* Query command codes (answered at once). */
enum s3g_query {
	S3G_Q_VERSION = 0,
	S3G_Q_INIT = 1,
	S3G_Q_BUFFER_FREE = 2,
	S3G_Q_CLEAR_BUFFER = 3,
	S3G_Q_ABORT = 7,
	S3G_Q_PAUSE = 8,
	S3G_Q_TOOL_QUERY = 10,
	S3G_Q_IS_FINISHED = 11,
	S3G_Q_RESET = 17,
	S3G_Q_BUILD_NAME = 20,
	S3G_Q_POSITION_EXT = 21,
	S3G_Q_EXTENDED_STOP = 22,
	S3G_Q_BOARD_STATUS = 23,
	S3G_Q_BUILD_STATS = 24,
	S3G_Q_ADVANCED_VERSION = 27,
};

/* Tool query sub-commands (query 10) and tool action sub-commands (136). */
enum s3g_tool_cmd {
	S3G_TQ_VERSION = 0,
	S3G_TQ_TEMP = 2,
	S3G_TQ_TOOL_READY = 22,
	S3G_TQ_PLATFORM_TEMP = 30,
	S3G_TQ_TARGET = 32,
	S3G_TQ_PLATFORM_TARGET = 33,
	S3G_TQ_PLATFORM_READY = 35,
	S3G_TA_SET_TEMP = 3,
	S3G_TA_MOTOR = 10,
	S3G_TA_FAN = 12,
	S3G_TA_SET_PLATFORM_TEMP = 31,
};

/* Build states in the build statistics (query 24). */
enum s3g_build_state {
	S3G_BUILD_NONE = 0, /* boot-up state */
	S3G_BUILD_RUNNING = 1,
	S3G_BUILD_FINISHED = 2,
	S3G_BUILD_PAUSED = 3,
	S3G_BUILD_CANCELED = 4,
	S3G_BUILD_SLEEPING = 5,
};

/* ---- framing ---------------------------------------------------------- */

/* s3g_crc_update - one byte into the CRC-8 (iButton/Maxim, reflected 0x8C). */
uint8_t s3g_crc_update(uint8_t crc, uint8_t byte);

/* s3g_crc - CRC of n bytes from 0; "123456789" gives 0xA1. */
uint8_t s3g_crc(const uint8_t *p, size_t n);

/*
 * s3g_encode - frame a payload of len (1..S3G_MAX_PAYLOAD) bytes into out
 * (cap >= len + 3).  Returns the packet length, or ST_ERR_ARG (empty or
 * over-long payload, small buffer) with err filled.
 */
int s3g_encode(const uint8_t *payload, size_t len, uint8_t *out, size_t cap,
	       struct st_error *err);

/* Framer results below zero: why *consumed bytes were skipped. */
enum s3g_frame_skip {
	S3G_SKIP_NOISE = -1,	  /* bytes before a start byte */
	S3G_SKIP_BAD_LENGTH = -2, /* start byte followed by a length > 32 */
	S3G_SKIP_BAD_CRC = -3,	  /* whole packet, CRC wrong: start byte skipped */
};

/*
 * s3g_frame - find one packet at the start of buf[0..len).
 * Returns > 0: a packet of *consumed bytes, its payload at buf + 2 with
 *              *plen bytes (may be 0);
 *         0:   need more bytes (*consumed 0);
 *         < 0: an enum s3g_frame_skip; drop *consumed bytes and call again
 *              (after a bad length or CRC only the start byte is dropped,
 *              so a real packet hidden behind it is still found).
 */
int s3g_frame(const uint8_t *buf, size_t len, size_t *consumed, size_t *plen);

/* ---- tables ------------------------------------------------------------ */

/* s3g_rc_action - the host action for a response code (unknown: FAIL). */
enum s3g_action s3g_rc_action(uint8_t rc);

/* s3g_rc_name - "success", "buffer overflow", ...; "unknown" otherwise. */
const char *s3g_rc_name(uint8_t rc);

/* s3g_command_name - short name of a query or action command code
 * ("queue point x3g", ...), or "unknown". */
const char *s3g_command_name(uint8_t code);

/*
 * s3g_action_length - length in bytes (code byte included) of the action
 * command at buf[0..avail), as the firmware's command buffer parser sees
 * it: fixed per code, or from the embedded length (136) or the NUL that
 * ends the text (149, 153).  Returns > 0, 0 if more bytes are needed to
 * tell, or ST_ERR_UNSUPPORTED for a code that is not an action command
 * the firmware knows.
 */
int s3g_action_length(const uint8_t *buf, size_t avail);

/* ---- driver ------------------------------------------------------------ */

/* Driver options; s3g_options_init fills the defaults. */
struct s3g_options {
	int timeout_ms;		 /* wait for a reply (ms); default 1000 (GPX: 1 s) */
	int max_retries;	 /* time-outs per packet; default 5 (s3g doc) */
	int max_rejects;	 /* retryable error or damaged replies per packet; default 30:
				  * the printer answers, so the link is alive but
				  * noisy, and at 1 % of bytes hit 30 % of 35-byte
				  * packets are spoilt: 5 tries give up once in
				  * 1 400 packets, 30 once in 10^15 */
	int overflow_deadline_ms; /* buffer full with no progress (ms); default 300000 */
	int poll_ms;		 /* free-space poll interval when full (ms); default 5 */
	int stats_ms;		 /* reset check interval while streaming (ms); default 1000 */
	int quiet_ms;		 /* line must be silent this long after an error (ms); default 10 */
	bool wait_finished;	 /* s3g_stream waits until the printer is idle; default true */
	int tools;		 /* extruders whose temperatures are read: 1 (default) or 2 */
};

/* Why a stream ended early, for the caller's exit status. */
enum s3g_fail {
	S3G_FAIL_NONE = 0,
	S3G_FAIL_LINK,	  /* unplugged, reset, no answer, a line too noisy */
	S3G_FAIL_PRINTER, /* the printer stopped or refused the build, or its
			   * buffer stayed full: cancelled on its panel, overheat */
	S3G_FAIL_SOURCE,  /* the command source failed or gave a bad command */
};

/* Status and counters, filled by s3g_stream (and by every exchange). */
struct s3g_status {
	size_t total;		 /* commands in the stream */
	size_t confirmed;	 /* commands answered with success (or resolved as queued) */
	size_t skipped;		 /* commands answered "unsupported" */
	uint64_t packets;	 /* packets written, resends and queries included */
	uint64_t retries;	 /* resends after retryable errors and time-outs */
	uint64_t overflows;	 /* buffer-overflow replies */
	uint64_t errors;	 /* error replies of any kind */
	uint64_t timeouts;	 /* replies missing: the full time-out went by */
	uint64_t garbled;	 /* replies that came damaged: settled as soon as
				  * the line went quiet (quiet_ms), no time-out */
	uint64_t misread;	 /* actions answered with a query's data: damaged
				  * past the CRC, sent again */
	uint64_t resolved;	 /* time-outs settled by asking the firmware */
	uint64_t dup_risk;	 /* action packets resent without being able to tell */
	uint64_t drifts;	 /* times the build's line count was found off from the
				  * commands confirmed (a packet damaged past CRC-8 ran
				  * as another number of commands) and re-based */
	uint64_t bytes_out, bytes_in;
	uint64_t action_bytes;	 /* bytes of confirmed action payloads */
	uint32_t buffer_free;	 /* last reported free buffer space (bytes) */
	int tool_temp, tool_target, platform_temp, platform_target; /* degC */
	int tool1_temp, tool1_target; /* the second extruder's (options.tools 2), degC */
	uint32_t line;		 /* firmware's line number (commands processed) */
	int build_state;	 /* enum s3g_build_state, -1 unknown */
	double elapsed_s;	 /* since s3g_stream started */
	bool interrupted;	 /* *stop was set */
	enum s3g_fail fail;	 /* why the last failed call failed */
};

/* One action command payload for s3g_stream (one packet each). */
struct s3g_cmd {
	const uint8_t *payload;
	uint8_t len;
};

/* Build statistics (query 24). */
struct s3g_build_stats {
	uint8_t state;		 /* enum s3g_build_state */
	uint8_t hours, minutes;
	uint32_t line;		 /* commands processed since build start */
};

/* Extended position (query 21). */
struct s3g_position {
	int32_t steps[5];	 /* X Y Z A B */
	uint16_t endstops;
};

/* Temperatures of tool 0, the platform and (options.tools 2) tool 1 (degC). */
struct s3g_temps {
	int tool, tool_target, platform, platform_target;
	int tool1, tool1_target; /* 0 with one tool */
};

/* Progress callback: called about every 100 ms while streaming. */
typedef void (*s3g_progress_fn)(void *ctx, const struct s3g_status *st);

struct s3g;

/* s3g_options_init - fill o with the defaults listed above. */
void s3g_options_init(struct s3g_options *o);

/*
 * s3g_new - a driver over an open transport x (still the caller's; close
 * it after s3g_free).  opts may be NULL.  Returns 0, ST_ERR_ARG or
 * ST_ERR_NOMEM; *out NULL on error.
 */
int s3g_new(struct xport *x, const struct s3g_options *opts, struct s3g **out,
	    struct st_error *err);

/* s3g_free - free the driver (not the transport); NULL is safe. */
void s3g_free(struct s3g *s);

/* s3g_status_get - the counters so far (never NULL for a live driver). */
const struct s3g_status *s3g_status_get(const struct s3g *s);

/*
 * s3g_transact - send one payload (1..32 bytes) and return the reply
 * payload in resp (cap >= S3G_MAX_PAYLOAD recommended; *rlen its length),
 * applying the retry policy: returns 0 with resp[0] == S3G_RC_OK, or with
 * resp[0] == S3G_RC_UNSUPPORTED (skip); otherwise ST_ERR_IO (no answer
 * after the retries, printer unplugged, a stopping code) or ST_ERR_RANGE
 * (a reply too short for what was asked), err naming the command.
 */
int s3g_transact(struct s3g *s, const uint8_t *payload, size_t len, uint8_t *resp, size_t cap,
		 size_t *rlen, struct st_error *err);

/* Queries; each returns 0 or the s3g_transact errors. */
int s3g_get_version(struct s3g *s, uint16_t host_version, uint16_t *fw, struct st_error *err);
int s3g_get_buffer_free(struct s3g *s, uint32_t *free_bytes, struct st_error *err);
int s3g_get_temps(struct s3g *s, struct s3g_temps *t, struct st_error *err);
int s3g_is_finished(struct s3g *s, bool *done, struct st_error *err);
int s3g_get_position(struct s3g *s, struct s3g_position *p, struct st_error *err);
int s3g_get_build_stats(struct s3g *s, struct s3g_build_stats *b, struct st_error *err);
int s3g_get_board_status(struct s3g *s, uint8_t *bits, struct st_error *err);

/*
 * s3g_cancel - a safe stop: abort (query 7: motion stops, buffer cleared,
 * the board soft-resets), then heaters off (tools 0 and 1 and platform to
 * 0 degC) and steppers off.  Returns 0 or the first error.
 */
int s3g_cancel(struct s3g *s, struct st_error *err);

/*
 * s3g_stream - send n action commands in order, one packet each, keeping
 * the command buffer full: the free space is learnt with query 2 and the
 * bytes sent since are subtracted, so a packet is only sent when it fits
 * (a buffer-overflow reply is still handled).  Every payload must be a
 * whole action command (code >= 128, length as s3g_action_length says).
 * progress (may be NULL) is called about every 100 ms with ctx; stop (may
 * be NULL) is polled between packets: when set, streaming ends with
 * status.interrupted and returns 0 (the caller then calls s3g_cancel).
 * With opts.wait_finished the call returns when the printer is idle.
 * st (may be NULL) receives the final status.
 * Returns 0, ST_ERR_ARG (a bad payload, naming its index), or ST_ERR_IO
 * (unplugged, reset, no answer, the printer stopped the build), the
 * message naming the last confirmed command.
 */
int s3g_stream(struct s3g *s, const struct s3g_cmd *cmds, size_t n, s3g_progress_fn progress,
	       void *ctx, volatile sig_atomic_t *stop, struct s3g_status *st,
	       struct st_error *err);

/* Longest build name s3g_frame_builds keeps: 153 is code, uint32, text,
 * NUL in one payload. */
#define S3G_FRAME_NAME_MAX (S3G_MAX_PAYLOAD - 6)

/*
 * s3g_frame_builds - from now on, a stream whose first command is not a
 * build start (153) is framed as ReplicatorG frames a build over USB: a
 * 153 named name (cut to S3G_FRAME_NAME_MAX) goes first, and a build end
 * (154) last unless the stream's own last command is one.  Outside a
 * build Sailfish reports no line count, and the line count is what
 * settles a lost reply (see "Exactly once").  The framing commands are
 * not counted in status.confirmed.  NULL or "" turns it off (the default).
 */
void s3g_frame_builds(struct s3g *s, const char *name);

/*
 * s3g_source_fn - the command source of s3g_stream_pull: fill *cmd with the
 * next action command, its payload valid until the next call.  Returns 1,
 * 0 at the end of the stream, or a negative class with err filled (the
 * stream then ends with that class and S3G_FAIL_SOURCE).
 */
typedef int (*s3g_source_fn)(void *src, struct s3g_cmd *cmd, struct st_error *err);

/* Commands whose lengths the stream remembers for settling lost replies;
 * enough for a command buffer of 2 x this many bytes (Sailfish: 512). */
#define S3G_STREAM_HISTORY 4096

/*
 * s3g_stream_pull - s3g_stream with commands pulled one at a time from
 * next(src, ...), so a caller can translate G-code as it streams with
 * bounded memory.  Each command is checked as it comes: a bad one ends the
 * stream with ST_ERR_ARG after the commands before it were sent.  total is
 * the number of commands expected (0 if unknown), for status.total and
 * messages.  Returns, stops and reports as s3g_stream; status.fail says
 * why a failed stream ended.
 */
int s3g_stream_pull(struct s3g *s, s3g_source_fn next, void *src, size_t total,
		    s3g_progress_fn progress, void *ctx, volatile sig_atomic_t *stop,
		    struct s3g_status *st, struct st_error *err);

#endif /* STRATUM_SERIAL_S3G_H */
