/*
 * x3gtest.h - what the x3g suite's files share (check_x3g.c,
 * check_x3g_gpx.c): a translator for the Creator Pro fed G-code lines, with
 * its output and warnings, and little-endian bytes for expected payloads.
 */
#ifndef STRATUM_TESTS_X3GTEST_H
#define STRATUM_TESTS_X3GTEST_H

#include <stddef.h>
#include <stdint.h>

#include "x3g.h"

#define OUT_MAX 4096

/* Bytes of a little-endian int32 / uint16, for writing expected payloads. */
#define LE32(v) (uint8_t)((uint32_t)(v)&0xff), (uint8_t)(((uint32_t)(v) >> 8) & 0xff), \
		(uint8_t)(((uint32_t)(v) >> 16) & 0xff), (uint8_t)(((uint32_t)(v) >> 24) & 0xff)
#define LE16(v) (uint8_t)((v)&0xff), (uint8_t)(((v) >> 8) & 0xff)

/* A translator and what it wrote. */
struct tr {
	struct x3g_translator *t;
	uint8_t out[OUT_MAX];
	size_t len;
	size_t warnings;
	char warning[X3G_WARNING_MAX];
	uint64_t warning_line;
};

#define RR X3G_FLAVOR_REPRAP
#define MB X3G_FLAVOR_MAKERBOT

/* A fresh translator of flavor for the Creator Pro into r. */
void tr_open(struct tr *r, enum x3g_flavor flavor);
/* Collect the output and the warnings of the last call. */
void tr_collect(struct tr *r);
/* Translate each line of text (lines numbered from 1), appending output. */
void tr_lines(struct tr *r, const char *text);

#endif
