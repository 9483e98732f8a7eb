/*
 * s3g_frame.c - S3G framing (CRC, packets) and the tables of response
 * codes and action commands (s3g.h; docs/protocols.md section 2).
 */
#include <stddef.h>
#include <stdint.h>
#include <string.h>

#include "s3g.h"

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
