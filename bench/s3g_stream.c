/*
 * s3g_stream.c - bench/run.sh s3g: stream an X3G file's commands to a port
 * with the S3G driver (serial/s3g.h) and print the figures as JSON.
 * usage: s3g_stream PORT FILE.x3g BAUD
 */
#include <stdio.h>
#include <stdlib.h>
#include <string.h>

#include "s3g.h"
#include "xport.h"

int main(int argc, char **argv)
{
	struct st_error err = {0};
	struct xport *x = NULL;
	struct s3g *d = NULL;
	struct s3g_status st;
	if (argc != 4) {
		fprintf(stderr, "usage: s3g_stream PORT FILE.x3g BAUD\n");
		return 2;
	}
	int baud = atoi(argv[3]);
	FILE *f = fopen(argv[2], "rb");
	if (!f) {
		perror(argv[2]);
		return 65;
	}
	size_t cap = 1 << 20, len = 0, n = 0;
	uint8_t *buf = malloc(cap);
	struct s3g_cmd *cmds = malloc(cap / 2 * sizeof(*cmds));
	if (!buf || !cmds)
		return 70;
	len = fread(buf, 1, cap, f);
	fclose(f);
	for (size_t off = 0; off < len;) {
		int k = s3g_action_length(buf + off, len - off);
		if (k <= 0 || k > S3G_MAX_PAYLOAD) {
			fprintf(stderr, "%s: undecodable command at byte %zu\n", argv[2], off);
			return 65;
		}
		cmds[n++] = (struct s3g_cmd){buf + off, (uint8_t)k};
		off += (size_t)k;
	}
	struct xport_options xo = {.baudrate = baud};
	if (xport_open(argv[1], &xo, &x, &err) || s3g_new(x, NULL, &d, &err)) {
		fprintf(stderr, "%s\n", err.msg);
		return 69;
	}
	int rc = s3g_stream(d, cmds, n, NULL, NULL, NULL, &st, &err);
	if (rc)
		fprintf(stderr, "%s\n", err.msg);
	double link = baud / 10.0;
	printf("{\n  \"commands\": %zu,\n  \"confirmed\": %zu,\n  \"packets\": %llu,\n"
	       "  \"bytes\": %llu,\n  \"action_bytes\": %llu,\n  \"retries\": %llu,\n"
	       "  \"seconds\": %.3f,\n  \"commands_per_s\": %.1f,\n  \"bytes_per_s\": %.0f,\n"
	       "  \"link_fraction\": %.3f\n}\n",
	       n, st.confirmed, (unsigned long long)st.packets, (unsigned long long)st.bytes_out,
	       (unsigned long long)st.action_bytes, (unsigned long long)st.retries, st.elapsed_s,
	       st.confirmed / st.elapsed_s, st.bytes_out / st.elapsed_s,
	       (st.bytes_out + st.bytes_in) / st.elapsed_s / link);
	s3g_free(d);
	xport_close(x);
	free(buf);
	free(cmds);
	return rc ? 1 : 0;
}
