/*
 * print_double.c - the test double behind `port = test-instant` (print.h):
 * it "prints" a G-code file by reading it line by line through our parser,
 * so a file that is not G-code fails as it would on a printer, reports the
 * byte position as progress, takes temperatures from M104/M109/M140/M190 as
 * reached at once, and waits out G4 dwells (which lets tests hold a print
 * in progress).  It never touches a port.  A testing aid only.
 */
#include <errno.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>
#include <sys/stat.h>
#include <time.h>

#include "gcode.h"
#include "print.h"

#define DOUBLE_DWELL_MAX_MS 60000 /* longest G4 honoured, ms */

struct double_state {
	char name[NODE_NAME_MAX];
};

static int double_connect(const struct node_printer_config *pc, const struct profile *prof,
			  void **state, struct st_error *err)
{
	struct double_state *s = calloc(1, sizeof(*s));

	(void)prof;
	if (!s)
		return st_error_set(err, ST_ERR_NOMEM, "printer %s: out of memory", pc->name);
	snprintf(s->name, sizeof(s->name), "%s", pc->name);
	*state = s;
	return 0;
}

static void double_disconnect(void *state)
{
	free(state);
}

/* The value of word letter of l, or dflt. */
static double word(const struct gcode_line *l, char letter, double dflt)
{
	for (size_t i = 0; i < l->nwords; i++)
		if (l->words[i].letter == letter && l->words[i].has_value)
			return l->words[i].value;
	return dflt;
}

/* Temperatures a line sets; ctl->mu held. */
static void apply_temps(const struct gcode_line *l, struct node_print_ctl *ctl)
{
	if (l->letter != 'M')
		return;
	if (l->number == 104 || l->number == 109) {
		ctl->tool_target = word(l, 'S', ctl->tool_target);
		ctl->tool_actual = ctl->tool_target;
	} else if (l->number == 140 || l->number == 190) {
		ctl->bed_target = word(l, 'S', ctl->bed_target);
		ctl->bed_actual = ctl->bed_target;
	}
}

/* Deadline ms from now on CLOCK_REALTIME (the condition variable's clock). */
static struct timespec deadline_ms(long ms)
{
	struct timespec t;

	clock_gettime(CLOCK_REALTIME, &t);
	t.tv_sec += ms / 1000;
	t.tv_nsec += (ms % 1000) * 1000000L;
	if (t.tv_nsec >= 1000000000L) {
		t.tv_sec++;
		t.tv_nsec -= 1000000000L;
	}
	return t;
}

/*
 * Hold while paused, for up to dwell_ms besides (0: no dwell); ctl->mu held.
 * Returns -1 to go on, else the node_print_result that ends the print.
 */
static int wait_requests(struct node_print_ctl *ctl, long dwell_ms)
{
	struct timespec until = deadline_ms(dwell_ms);
	int rc = 0;

	for (;;) {
		if (ctl->stop)
			return NODE_PRINT_STOPPED;
		if (ctl->cancel)
			return NODE_PRINT_CANCELLED;
		ctl->paused = ctl->pause;
		if (ctl->pause) {
			pthread_cond_wait(&ctl->cv, &ctl->mu);
			continue;
		}
		if (dwell_ms <= 0 || rc == ETIMEDOUT)
			return -1;
		rc = pthread_cond_timedwait(&ctl->cv, &ctl->mu, &until);
	}
}

static int double_print(void *state, const char *path, int64_t start, bool resume,
			struct node_print_ctl *ctl, struct st_error *err)
{
	FILE *f = fopen(path, "rb");
	char *line = NULL;
	size_t cap = 0;
	ssize_t n;
	long lineno = 0;
	int64_t pos = start;
	struct stat st;
	int result = NODE_PRINT_DONE;

	(void)state;
	(void)resume; /* nothing to restore: the double keeps no position */
	if (!f)
		return st_error_set(err, ST_ERR_IO, "%s: cannot open: %s", path, strerror(errno));
	if (fstat(fileno(f), &st) || fseeko(f, (off_t)start, SEEK_SET)) {
		result = st_error_set(err, ST_ERR_IO, "%s: cannot read: %s", path, strerror(errno));
		goto out_close;
	}
	pthread_mutex_lock(&ctl->mu);
	ctl->size = st.st_size;
	ctl->filepos = pos;
	pthread_mutex_unlock(&ctl->mu);
	while ((n = getline(&line, &cap, f)) > 0) {
		struct gcode_line l;
		long dwell = 0;
		int r;

		lineno++;
		if (gcode_parse(line, (size_t)n, 0, &l, err)) {
			char why[sizeof(err->msg)];

			snprintf(why, sizeof(why), "%s", err->msg);
			result = start ? st_error_set(err, ST_ERR_PARSE, "%s: byte %lld: %s", path,
						      (long long)pos, why)
				       : st_error_set(err, ST_ERR_PARSE, "%s: line %ld: %s", path,
						      lineno, why);
			goto out_free;
		}
		if (l.letter == 'G' && l.number == 4)
			dwell = (long)(word(&l, 'P', 0) + 1000 * word(&l, 'S', 0));
		if (dwell > DOUBLE_DWELL_MAX_MS)
			dwell = DOUBLE_DWELL_MAX_MS;
		pos += n;
		pthread_mutex_lock(&ctl->mu);
		apply_temps(&l, ctl);
		ctl->filepos = pos;
		r = wait_requests(ctl, dwell);
		pthread_mutex_unlock(&ctl->mu);
		if (r >= 0) {
			result = r;
			goto out_free;
		}
	}
	if (ferror(f))
		result = st_error_set(err, ST_ERR_IO, "%s: read error at byte %lld", path,
				      (long long)pos);
out_free:
	free(line);
out_close:
	fclose(f);
	return result;
}

static int double_command(void *state, const char *text, struct st_error *err)
{
	struct gcode_line l;

	(void)state;
	return gcode_parse(text, strlen(text), 0, &l, err);
}

const struct node_printer_ops node_double_ops = {
	.name = "test-instant",
	.can_resume = true,
	.connect = double_connect,
	.disconnect = double_disconnect,
	.print = double_print,
	.command = double_command,
};
