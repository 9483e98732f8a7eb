/*
 * util.c - the scripted transport and the temporary folder of fuzz.h.
 * The transport is polled like the others: its descriptor is a pipe that
 * holds one byte while there is something to read.  It runs on a clock of
 * its own (xport_clock_s): only the host's writes change what the script
 * lets through, so a wait that finds nothing to read would find nothing at
 * its end either, and the clock jumps there instead of sleeping.
 */
#include "fuzz.h"

#include <fcntl.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>
#include <sys/stat.h>
#include <unistd.h>

#include "xport_impl.h"

/* What the scripted printer has left to say. */
struct script {
	uint8_t *data;
	size_t len, pos;
	size_t *ends, nturns, turn; /* bytes before ends[turn] may be read */
	int pipe[2];
	bool ready;		    /* the pipe holds its byte */
	int64_t now_us;		    /* the simulated clock */
};

/* Time a look at the clock costs, as on a real one: a loop that only
 * watches the clock still reaches its deadline. */
#define SCRIPT_LOOK_US 10

/* Keep the pipe readable exactly while bytes of this turn are left. */
static void script_signal(struct script *s)
{
	bool want = s->pos < s->ends[s->turn] || s->pos == s->len;
	char b = 0;

	if (want && !s->ready)
		s->ready = write(s->pipe[1], &b, 1) == 1;
	else if (!want && s->ready)
		s->ready = read(s->pipe[0], &b, 1) != 1;
}

static long script_read(struct xport *x, void *buf, size_t cap)
{
	struct script *s = x->priv;
	size_t n, piece = (s->pos * 7) % 61 + 1; /* lines and packets arrive split */

	if (s->pos == s->len)
		return XPORT_STEP_GONE;
	n = s->ends[s->turn] - s->pos;
	if (!n)
		return XPORT_STEP_AGAIN;
	if (n > piece)
		n = piece;
	if (n > cap)
		n = cap;
	memcpy(buf, s->data + s->pos, n);
	s->pos += n;
	script_signal(s);
	return (long)n;
}

static long script_write(struct xport *x, const void *buf, size_t len)
{
	struct script *s = x->priv;

	(void)buf;
	if (s->turn + 1 < s->nturns)
		s->turn++;
	script_signal(s);
	return (long)len;
}

static long script_outq(struct xport *x)
{
	(void)x;
	return 0;
}

static void script_close(struct xport *x)
{
	struct script *s = x->priv;

	if (!s)
		return;
	close(s->pipe[0]);
	close(s->pipe[1]);
	free(s->data);
	free(s->ends);
	free(s);
}

static int64_t script_clock_us(struct xport *x)
{
	struct script *s = x->priv;

	return s->now_us += SCRIPT_LOOK_US;
}

static void script_pause_ms(struct xport *x, int ms)
{
	struct script *s = x->priv;

	if (ms > 0)
		s->now_us += (int64_t)ms * 1000;
}

static const struct xport_ops script_ops = {
	.name = "fuzz",
	.read = script_read,
	.write = script_write,
	.outq = script_outq,
	.close = script_close,
	.clock_us = script_clock_us,
	.pause_ms = script_pause_ms,
};

struct xport *fuzz_xport_new(const uint8_t *data, size_t len, const size_t *ends,
			     size_t nturns)
{
	struct xport *x = calloc(1, sizeof(*x));
	struct script *s = calloc(1, sizeof(*s));

	if (s)
		s->pipe[0] = s->pipe[1] = -1;
	if (!x || !s || !nturns || ends[nturns - 1] != len)
		goto out_free;
	s->data = malloc(len ? len : 1);
	s->ends = malloc(nturns * sizeof(*s->ends));
	x->spec = strdup("fuzz");
	if (!s->data || !s->ends || !x->spec || pipe(s->pipe))
		goto out_free;
	fcntl(s->pipe[0], F_SETFL, O_NONBLOCK);
	fcntl(s->pipe[1], F_SETFL, O_NONBLOCK);
	memcpy(s->data, data, len);
	memcpy(s->ends, ends, nturns * sizeof(*s->ends));
	s->len = len;
	s->nturns = nturns;
	s->now_us = 1000000000; /* 1000 s: well past zero, which drivers read as "never" */
	x->ops = &script_ops;
	x->backend = XPORT_BACKEND_FD;
	x->kind = "fuzz";
	x->fd = s->pipe[0];
	x->priv = s;
	snprintf(x->desc, sizeof(x->desc), "fuzz transport");
	script_signal(s);
	return x;

out_free:
	if (s) {
		if (s->pipe[0] >= 0) {
			close(s->pipe[0]);
			close(s->pipe[1]);
		}
		free(s->data);
		free(s->ends);
	}
	free(s);
	if (x)
		free(x->spec);
	free(x);
	return NULL;
}

static char tmpdir[256];

static void remove_tmpdir(void)
{
	char cmd[300];

	if (tmpdir[0] && snprintf(cmd, sizeof(cmd), "rm -rf '%s'", tmpdir) < (int)sizeof(cmd) &&
	    system(cmd))
		fprintf(stderr, "fuzz: could not remove %s\n", tmpdir);
}

const char *fuzz_tmpdir(void)
{
	if (!tmpdir[0]) {
		const char *base = getenv("TMPDIR");
		struct stat st;

		/* Targets write a file per input: in memory (tmpfs) rather than
		 * on a disk, whose file system (ext4) writes a file truncated
		 * and rewritten out at each close. */
		if (!base)
			base = !stat("/dev/shm", &st) && S_ISDIR(st.st_mode) ? "/dev/shm" : "/tmp";
		snprintf(tmpdir, sizeof(tmpdir), "%s/stratum-fuzz-XXXXXX", base);
		if (!mkdtemp(tmpdir)) {
			perror("fuzz: mkdtemp");
			abort();
		}
		atexit(remove_tmpdir);
	}
	return tmpdir;
}
