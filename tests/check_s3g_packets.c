/*
 * check_s3g_packets.c - the S3G packet layer (serial/s3g*.c), part of the
 * s3g suite (check_s3g.c): CRC vectors, the encoder's limits, framing and
 * resync, and the command tables.
 */
#include <check.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>

#include "s3g.h"
#include "suites.h"

START_TEST(crc_vectors)
{
	ck_assert_uint_eq(s3g_crc((const uint8_t *)"123456789", 9), 0xA1);
	/* Dallas/Maxim table entries and the ROM code of application note 27 */
	const uint8_t one = 0x01, two = 0x02, rom[7] = {0x02, 0x1C, 0xB8, 0x01, 0, 0, 0};
	ck_assert_uint_eq(s3g_crc(&one, 1), 0x5E);
	ck_assert_uint_eq(s3g_crc(&two, 1), 0xBC);
	ck_assert_uint_eq(s3g_crc(rom, 7), 0xA2);
	ck_assert_uint_eq(s3g_crc(NULL, 0), 0);
	/* the "get available buffer size" query GPX sends: D5 01 02 BC */
	uint8_t pkt[8], q = 2;
	ck_assert_int_eq(s3g_encode(&q, 1, pkt, sizeof(pkt), NULL), 4);
	ck_assert_uint_eq(pkt[0], 0xD5);
	ck_assert_uint_eq(pkt[1], 1);
	ck_assert_uint_eq(pkt[2], 2);
	ck_assert_uint_eq(pkt[3], 0xBC);
}
END_TEST

START_TEST(encode_limits)
{
	uint8_t p[40] = {0}, out[64];
	struct st_error err = {0};
	ck_assert_int_eq(s3g_encode(p, 0, out, sizeof(out), &err), ST_ERR_ARG);
	ck_assert_int_eq(s3g_encode(p, 33, out, sizeof(out), &err), ST_ERR_ARG);
	ck_assert_ptr_nonnull(strstr(err.msg, "33 bytes"));
	ck_assert_int_eq(s3g_encode(p, 32, out, 34, &err), ST_ERR_ARG);
	ck_assert_int_eq(s3g_encode(p, 32, out, 35, &err), 35);
}
END_TEST

START_TEST(frame_round_trip_and_resync)
{
	uint8_t stream[256], pay[32];
	size_t len = 0, used, n;
	/* garbage, a damaged packet, a bad length, then two good packets */
	const uint8_t junk[] = {0x00, 0x81, 0xFF};
	memcpy(stream, junk, sizeof(junk));
	len += sizeof(junk);
	for (int i = 0; i < 32; i++)
		pay[i] = (uint8_t)(i * 7 + 1);
	int k = s3g_encode(pay, 32, stream + len, sizeof(stream) - len, NULL);
	ck_assert_int_eq(k, 35);
	stream[len + 10] ^= 0x10; /* CRC now wrong */
	len += (size_t)k;
	stream[len++] = 0xD5;
	stream[len++] = 200; /* impossible length */
	k = s3g_encode(pay, 5, stream + len, sizeof(stream) - len, NULL);
	len += (size_t)k;
	k = s3g_encode(pay + 5, 20, stream + len, sizeof(stream) - len, NULL);
	len += (size_t)k;

	size_t off = 0, got = 0, noise = 0, crc = 0, badlen = 0;
	while (off < len) {
		int f = s3g_frame(stream + off, len - off, &used, &n);
		if (f == 0)
			break;
		if (f > 0) {
			ck_assert_int_eq(memcmp(stream + off + 2, got == 0 ? pay : pay + 5, n), 0);
			ck_assert_uint_eq(n, got == 0 ? 5 : 20);
			got++;
		} else if (f == S3G_SKIP_NOISE) {
			noise++;
		} else if (f == S3G_SKIP_BAD_CRC) {
			crc++;
		} else if (f == S3G_SKIP_BAD_LENGTH) {
			badlen++;
		}
		ck_assert_uint_gt(used, 0);
		off += used;
	}
	ck_assert_uint_eq(got, 2);
	ck_assert_uint_ge(crc, 1);
	ck_assert_uint_eq(badlen, 1);
	ck_assert_uint_ge(noise, 1);
	ck_assert_uint_eq(off, len);
	/* a packet cut short needs more bytes */
	k = s3g_encode(pay, 10, stream, sizeof(stream), NULL);
	ck_assert_int_eq(s3g_frame(stream, 8, &used, &n), 0);
	ck_assert_int_eq(s3g_frame(stream, (size_t)k, &used, &n), 1);
	ck_assert_uint_eq(used, (size_t)k);
}
END_TEST

START_TEST(tables)
{
	uint8_t c[40] = {155};
	ck_assert_int_eq(s3g_action_length(c, 1), 32);
	c[0] = 139;
	ck_assert_int_eq(s3g_action_length(c, 1), 25);
	c[0] = 142;
	ck_assert_int_eq(s3g_action_length(c, 1), 26);
	const uint8_t tool[] = {136, 0, 3, 2, 200, 0};
	ck_assert_int_eq(s3g_action_length(tool, 3), 0);
	ck_assert_int_eq(s3g_action_length(tool, sizeof(tool)), 6);
	const uint8_t name[] = {153, 0, 0, 0, 0, 'a', 'b', 0};
	ck_assert_int_eq(s3g_action_length(name, 7), 0);
	ck_assert_int_eq(s3g_action_length(name, sizeof(name)), 8);
	c[0] = 2;
	ck_assert_int_eq(s3g_action_length(c, 1), ST_ERR_UNSUPPORTED);
	c[0] = 138;
	ck_assert_int_eq(s3g_action_length(c, 1), ST_ERR_UNSUPPORTED);
	ck_assert_int_eq(s3g_rc_action(S3G_RC_OK), S3G_ACT_NEXT);
	ck_assert_int_eq(s3g_rc_action(S3G_RC_BUFFER_OVERFLOW), S3G_ACT_WAIT_RESEND);
	ck_assert_int_eq(s3g_rc_action(S3G_RC_CRC_MISMATCH), S3G_ACT_RETRY);
	ck_assert_int_eq(s3g_rc_action(S3G_RC_PACKET_TIMEOUT), S3G_ACT_RETRY);
	ck_assert_int_eq(s3g_rc_action(S3G_RC_GENERIC_ERROR), S3G_ACT_RETRY);
	ck_assert_int_eq(s3g_rc_action(S3G_RC_UNSUPPORTED), S3G_ACT_SKIP);
	ck_assert_int_eq(s3g_rc_action(S3G_RC_CANCEL_BUILD), S3G_ACT_STOP);
	ck_assert_int_eq(s3g_rc_action(S3G_RC_BOT_BUILDING), S3G_ACT_FAIL);
	ck_assert_str_eq(s3g_rc_name(0x82), "buffer overflow");
}
END_TEST

void s3g_packets_tcases(Suite *s)
{
	TCase *unit = tcase_create("packets");
	tcase_add_test(unit, crc_vectors);
	tcase_add_test(unit, encode_limits);
	tcase_add_test(unit, frame_round_trip_and_resync);
	tcase_add_test(unit, tables);
	suite_add_tcase(s, unit);
}
