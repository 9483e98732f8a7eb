/*
 * node.c - the node's life cycle (node.h): data directory, queue recovery,
 * profiles, worker threads, the progress ticker, the HTTP server.
 */
#include <dirent.h>
#include <errno.h>
#include <math.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>
#include <sys/stat.h>
#include <time.h>
#include <unistd.h>

#include "node_int.h"

/* mkdir path unless it is already a directory. */
static int make_dir(const char *path, struct st_error *err)
{
	struct stat st;

	if (!mkdir(path, 0750) || (errno == EEXIST && !stat(path, &st) && S_ISDIR(st.st_mode)))
		return 0;
	return st_error_set(err, ST_ERR_IO, "%s: cannot create the directory: %s", path,
			    strerror(errno));
}

/* dst = dir + "/" + name, or an error when it does not fit. */
static int join(char *dst, size_t cap, const char *dir, const char *name, struct st_error *err)
{
	if (snprintf(dst, cap, "%s/%s", dir, name) >= (int)cap)
		return st_error_set(err, ST_ERR_RANGE, "%s/%s: path too long", dir, name);
	return 0;
}

/* Remove what uploads in progress left in tmp/ when the node last stopped
 * (a crash, a kill): the folder is the node's own, and at start no upload
 * is in progress, so every file in it is a leftover. */
static int clean_tmp(const char *dir, struct st_error *err)
{
	DIR *d = opendir(dir);
	struct dirent *e;
	int removed = 0;

	if (!d)
		return st_error_set(err, ST_ERR_IO, "%s: %s", dir, strerror(errno));
	while ((e = readdir(d))) {
		if (!strcmp(e->d_name, ".") || !strcmp(e->d_name, ".."))
			continue;
		if (unlinkat(dirfd(d), e->d_name, 0)) {
			int code = errno;

			closedir(d);
			return st_error_set(err, ST_ERR_IO, "%s/%s: cannot remove a partial upload: %s",
					    dir, e->d_name, strerror(code));
		}
		removed++;
	}
	closedir(d);
	if (removed)
		node_log("info", NULL, 0, "removed %d partial upload(s) from %s", removed, dir);
	return 0;
}

static int setup_printer(struct node *n, size_t i, struct st_error *err)
{
	struct node_printer *p = &n->printers[i];
	char files[NODE_PATH_MAX];
	struct st_error e = {0};
	int rc;

	p->node = n;
	p->cfg = &n->cfg.printers[i];
	pthread_mutex_init(&p->mu, NULL);
	pthread_cond_init(&p->cv, NULL);
	pthread_mutex_init(&p->ctl.mu, NULL);
	p->ctl.tool1_actual = p->ctl.tool1_target = NAN; /* until a driver reads it */
	pthread_mutex_init(&p->gc_mu, NULL);
	pthread_mutex_init(&p->slice_mu, NULL);
	p->want_connect = true; /* OctoPrint's autoconnect */
	rc = profile_find(p->cfg->profile, &p->prof, &e);
	if (rc)
		return st_error_set(err, rc, "%s: [printer %s]: %s", n->cfg.path, p->cfg->name,
				    e.msg);
	if ((rc = join(files, sizeof(files), n->cfg.data_dir, "files", err)) ||
	    (rc = make_dir(files, err)) ||
	    (rc = join(p->files_dir, sizeof(p->files_dir), files, p->cfg->name, err)) ||
	    (rc = make_dir(p->files_dir, err)))
		return rc;
	if (!strcmp(p->cfg->port, "sim")) {
		struct node_printer_config *pc = &n->cfg.printers[i];
		char sim[NODE_PATH_MAX];

		if ((rc = join(sim, sizeof(sim), n->cfg.data_dir, "sim", err)) ||
		    (rc = make_dir(sim, err)) ||
		    (rc = join(files, sizeof(files), sim, pc->name, err)) ||
		    (rc = snprintf(pc->sim_log, sizeof(pc->sim_log), "%s.log", files) >=
			  (int)sizeof(pc->sim_log)
			  ? st_error_set(err, ST_ERR_RANGE, "%s.log: path too long", files) : 0))
			return rc;
	}
	return 0;
}

int node_new(const struct node_config *cfg, struct node **out, struct st_error *err)
{
	struct node *n = calloc(1, sizeof(*n));
	char db[NODE_PATH_MAX];
	int rc, interrupted = 0, requeued = 0;

	*out = NULL;
	if (!n)
		return st_error_set(err, ST_ERR_NOMEM, "node: out of memory");
	n->cfg = *cfg;
	pthread_mutex_init(&n->tick_mu, NULL);
	pthread_mutex_init(&n->push_mu, NULL);
	pthread_cond_init(&n->push_cv, NULL);
	pthread_cond_init(&n->tick_cv, NULL);
	if ((rc = make_dir(cfg->data_dir, err)) ||
	    (rc = join(n->tmp_dir, sizeof(n->tmp_dir), cfg->data_dir, "tmp", err)) ||
	    (rc = make_dir(n->tmp_dir, err)) || (rc = clean_tmp(n->tmp_dir, err)) ||
	    (rc = join(n->sliced_dir, sizeof(n->sliced_dir), cfg->data_dir, "sliced", err)) ||
	    (rc = make_dir(n->sliced_dir, err)) ||
	    (rc = join(db, sizeof(db), cfg->data_dir, "queue.db", err)) ||
	    (rc = node_queue_open(db, &n->q, err)) ||
	    (rc = node_queue_recover(n->q, &interrupted, &requeued, err)))
		goto out_free;
	if (interrupted)
		node_log("warning", NULL, 0, "%d job(s) were printing when the node stopped: marked "
					     "interrupted, paused until an operator resumes or "
					     "cancels them", interrupted);
	if (requeued)
		node_log("info", NULL, 0, "%d job(s) were slicing: queued again", requeued);
	for (size_t i = 0; i < cfg->nprinters; i++) {
		n->nprinters = i + 1;
		if ((rc = setup_printer(n, i, err)))
			goto out_free;
	}
	*out = n;
	return 0;

out_free:
	node_free(n);
	return rc;
}

/* Keep p's temperatures in its history; p->mu held. */
static void sample_temps(struct node_printer *p)
{
	struct node_temp_sample *t = &p->temps[p->temps_next];

	pthread_mutex_lock(&p->ctl.mu);
	t->time = time(NULL);
	t->tool[0] = p->ctl.tool_actual;
	t->tool[1] = p->ctl.tool_target;
	t->bed[0] = p->ctl.bed_actual;
	t->bed[1] = p->ctl.bed_target;
	t->tool1[0] = p->ctl.tool1_actual;
	t->tool1[1] = p->ctl.tool1_target;
	p->temps_next = (p->temps_next + 1) % NODE_TEMP_HISTORY;
	if (p->ntemps < NODE_TEMP_HISTORY)
		p->ntemps++;
	pthread_mutex_unlock(&p->ctl.mu);
}

/* Store every print's position, so a crash loses at most NODE_TICK_MS of
 * it; sample the connected printers' temperatures every NODE_TEMP_EVERY ticks. */
static void *ticker_main(void *arg)
{
	struct node *n = arg;
	struct timespec t;
	unsigned ticks = 0;

	pthread_mutex_lock(&n->tick_mu);
	while (!n->ticker_stop) {
		clock_gettime(CLOCK_REALTIME, &t);
		t.tv_nsec += NODE_TICK_MS * 1000000L;
		t.tv_sec += t.tv_nsec / 1000000000L;
		t.tv_nsec %= 1000000000L;
		pthread_cond_timedwait(&n->tick_cv, &n->tick_mu, &t);
		for (size_t i = 0; i < n->nprinters; i++) {
			struct node_printer *p = &n->printers[i];
			int64_t pos, size;

			pthread_mutex_lock(&p->mu);
			if (p->job_printing) {
				pthread_mutex_lock(&p->ctl.mu);
				pos = p->ctl.filepos;
				size = p->ctl.size;
				pthread_mutex_unlock(&p->ctl.mu);
				node_queue_progress(n->q, p->job_id, pos, size);
			}
			if (p->connected && ticks % NODE_TEMP_EVERY == 0)
				sample_temps(p);
			pthread_mutex_unlock(&p->mu);
		}
		ticks++;
	}
	pthread_mutex_unlock(&n->tick_mu);
	return NULL;
}

int node_start(struct node *n, struct st_error *err)
{
	int rc;

	/* MQTT first: a node whose name another node holds on the broker stops
	 * here, before it opens a printer's port (and resets its board). */
	if ((rc = node_mqtt_start(n, err)))
		goto out_stop;
	if (pthread_create(&n->ticker, NULL, ticker_main, n)) {
		rc = st_error_set(err, ST_ERR_INTERNAL, "cannot start the progress thread");
		goto out_stop;
	}
	n->ticker_started = true;

	for (size_t i = 0; i < n->nprinters; i++) {
		struct node_printer *p = &n->printers[i];

		if (pthread_create(&p->thread, NULL, node_worker_main, p)) {
			rc = st_error_set(err, ST_ERR_INTERNAL, "cannot start the worker of %s",
					  p->cfg->name);
			goto out_stop;
		}
		p->thread_started = true;
	}
	n->started = true;
	if ((rc = node_http_start(n, err)))
		goto out_stop;
	node_mqtt_listening(n, n->port);
	node_log("info", NULL, 0, "node %s listening on %s:%u with %zu printer(s)", n->cfg.name,
		 n->cfg.listen_addr, n->port, n->nprinters);
	return 0;

out_stop:
	node_stop(n);
	return rc;
}

uint16_t node_port(const struct node *n)
{
	return n->port;
}

void node_stop(struct node *n)
{
	if (!n || n->stopped)
		return;
	n->stopped = true;
	node_mqtt_stop(n);
	node_http_stop(n);
	for (size_t i = 0; i < n->nprinters; i++) {
		struct node_printer *p = &n->printers[i];

		pthread_mutex_lock(&p->mu);
		p->stop = true;
		pthread_cond_signal(&p->cv);
		pthread_mutex_unlock(&p->mu);
		pthread_mutex_lock(&p->ctl.mu);
		p->ctl.stop = true;
		pthread_mutex_unlock(&p->ctl.mu);
	}
	for (size_t i = 0; i < n->nprinters; i++)
		if (n->printers[i].thread_started)
			pthread_join(n->printers[i].thread, NULL);
	if (n->ticker_started) {
		pthread_mutex_lock(&n->tick_mu);
		n->ticker_stop = true;
		pthread_cond_signal(&n->tick_cv);
		pthread_mutex_unlock(&n->tick_mu);
		pthread_join(n->ticker, NULL);
	}
	if (n->started)
		node_log("info", NULL, 0, "node %s stopped", n->cfg.name);
}

void node_free(struct node *n)
{
	if (!n)
		return;
	node_stop(n);
	for (size_t i = 0; i < n->nprinters; i++) {
		struct node_printer *p = &n->printers[i];

		profile_free(p->prof);
		pthread_mutex_destroy(&p->mu);
		pthread_cond_destroy(&p->cv);
		pthread_mutex_destroy(&p->ctl.mu);
		pthread_mutex_destroy(&p->gc_mu);
		pthread_mutex_destroy(&p->slice_mu);
		node_gcode_info_free(&p->gc);
	}
	node_queue_close(n->q);
	pthread_mutex_destroy(&n->tick_mu);
	pthread_mutex_destroy(&n->push_mu);
	pthread_cond_destroy(&n->push_cv);
	pthread_cond_destroy(&n->tick_cv);
	free(n);
}
