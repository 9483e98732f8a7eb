/*
 * http_queue.c - Stratum's queue API (docs/serve.md, "The queue API"):
 * what OctoPrint has no call for, under /api/stratum/ as OctoPrint puts a
 * plugin's under /api/plugin/NAME.  The printer's queue in order with
 * positions, one job, moving a queued job, cancelling it, queueing a
 * finished one again, and the operator's bed-clear confirmation.
 */
#include <errno.h>
#include <jansson.h>
#include <microhttpd.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>

#include "http_int.h"

/* The job number at the end of the path, or 0 when it is none. */
static int64_t job_id_of(const struct req *r)
{
	const char *s = http_tail(r);
	char *end = NULL;
	long long id;

	if (*s < '1' || *s > '9')
		return 0;
	errno = 0;
	id = strtoll(s, &end, 10);
	return errno || *end ? 0 : (int64_t)id;
}

/* Job id of r's printer into *j; false with a 404 answer sent in *ret. */
static bool find_job(struct node *n, struct MHD_Connection *c, struct req *r, int64_t id,
		     struct node_job *j, enum MHD_Result *ret)
{
	char msg[200];

	if (id && node_queue_get(n->q, id, j, NULL) == 1 && !strcmp(j->printer, r->p->cfg->name))
		return true;
	snprintf(msg, sizeof(msg), "no job %.40s on printer %s", http_tail(r), r->p->cfg->name);
	*ret = http_send_error(c, MHD_HTTP_NOT_FOUND, msg);
	return false;
}

json_t *http_queue_json(struct node *n, struct node_printer *p, const struct http_view *v)
{
	return json_pack("{s:b,s:o}", "bedClear", v->bed_clear, "waiting",
			 node_queue_waiting(n->q, p->cfg->name));
}

enum MHD_Result http_get_queue(struct node *n, struct MHD_Connection *c, struct req *r)
{
	struct http_view v;
	json_t *o;

	http_take_view(n, r->p, &v);
	o = json_pack("{s:s,s:s}", "printer", r->p->cfg->name, "state", http_state_text(&v));
	json_object_update_new(o, http_queue_json(n, r->p, &v));
	json_object_set_new(o, "active", v.has_job ? node_job_json(&v.job) : json_null());
	json_object_set_new(o, "jobs", node_queue_list(n->q, r->p->cfg->name, 200));
	return http_send_json(c, MHD_HTTP_OK, o, NULL);
}

enum MHD_Result http_get_queue_job(struct node *n, struct MHD_Connection *c, struct req *r)
{
	struct node_job j;
	enum MHD_Result ret;

	if (!find_job(n, c, r, job_id_of(r), &j, &ret))
		return ret;
	return http_send_json(c, MHD_HTTP_OK, node_job_json(&j), NULL);
}

/* The HTTP status of a queue command's error class. */
static unsigned error_status(int rc)
{
	return rc == ST_ERR_RANGE ? MHD_HTTP_CONFLICT : MHD_HTTP_INTERNAL_SERVER_ERROR;
}

/* {"command": "move", "position": N}: 204, or 400 / 409. */
static enum MHD_Result move_job(struct node *n, struct MHD_Connection *c, struct req *r,
				const struct node_job *j, json_t *body)
{
	json_t *pos = json_object_get(body, "position");
	struct st_error err = {0};
	int rc = node_control_move(n, r->p, j->id, json_is_integer(pos) ? json_integer_value(pos)
								       : 0, &err);

	if (rc == ST_ERR_ARG)
		return http_send_error(c, MHD_HTTP_BAD_REQUEST, err.msg);
	return rc ? http_send_error(c, error_status(rc), err.msg) : http_no_content(c);
}

enum MHD_Result http_post_queue_job(struct node *n, struct MHD_Connection *c, struct req *r)
{
	struct node_job j;
	struct st_error err = {0};
	enum MHD_Result ret;
	json_t *body;
	const char *cmd;
	int64_t id;
	int rc;

	if (!find_job(n, c, r, job_id_of(r), &j, &ret) || !(body = http_body_json(c, r, &ret)))
		return ret;
	cmd = json_string_value(json_object_get(body, "command"));
	if (cmd && !strcmp(cmd, "move")) {
		ret = move_job(n, c, r, &j, body);
	} else if (cmd && !strcmp(cmd, "cancel")) {
		rc = node_control_cancel(n, r->p, j.id, &err);
		ret = rc ? http_send_error(c, error_status(rc), err.msg) : http_no_content(c);
	} else if (cmd && !strcmp(cmd, "requeue")) {
		rc = node_control_requeue(n, r->p, j.id, &id, &err);
		if (rc) {
			ret = http_send_error(c, error_status(rc), err.msg);
		} else {
			char loc[2048], num[32];

			snprintf(num, sizeof(num), "%lld", (long long)id);
			http_url_for(c, r, "/api/stratum/queue/", num, loc, sizeof(loc));
			ret = node_queue_get(n->q, id, &j, &err) == 1
				      ? http_send_json(c, MHD_HTTP_CREATED, node_job_json(&j), loc)
				      : http_send_error(c, MHD_HTTP_INTERNAL_SERVER_ERROR, err.msg);
		}
	} else {
		ret = http_send_error(c, MHD_HTTP_BAD_REQUEST, "command is move, cancel or requeue");
	}
	json_decref(body);
	return ret;
}

enum MHD_Result http_post_bed_clear(struct node *n, struct MHD_Connection *c, struct req *r)
{
	struct node_printer *p = r->p;
	struct node_job j;
	struct st_error err = {0};
	enum MHD_Result ret;

	pthread_mutex_lock(&p->mu);
	if (p->job_id || node_queue_active(n->q, p->cfg->name, &j, NULL) == 1) {
		ret = http_send_error(c, MHD_HTTP_CONFLICT, "a job is on the printer (printing, paused "
						            "or interrupted); finish or cancel it first");
	} else if (node_queue_set_bed_clear(n->q, p->cfg->name, true, &err)) {
		ret = http_send_error(c, MHD_HTTP_INTERNAL_SERVER_ERROR, err.msg);
	} else {
		node_log("info", p->cfg->name, 0, "bed confirmed clear");
		pthread_cond_signal(&p->cv);
		ret = http_no_content(c);
	}
	pthread_mutex_unlock(&p->mu);
	return ret;
}
