/*
 * slicer.c - the slicing job: place, slice, run the stages into their own
 * layer stacks, merge them per layer, write G-code (see slicer.h).
 */
#include "slicer.h"

#include <math.h>
#include <pthread.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>
#include <unistd.h>

#include "grow.h"
#include "infill.h"
#include "overhang.h"
#include "stages.h"
#include "spiral.h"
#include "travel.h"

int slicer_place(const struct mesh *m, const struct slicer_bed *bed, double offset[3],
		 double min[3], double max[3], struct st_error *err)
{
	double lo[3], hi[3], at[2], size[3], placed_lo[3], placed_hi[3];

	if (!m || !bed || !offset || m->ntris == 0)
		return st_error_set(err, ST_ERR_ARG, "place: the mesh has no triangles");
	mesh_bbox(m, lo, hi);
	at[0] = bed->has_center ? bed->center_x : (bed->min_x + bed->max_x) / 2.0;
	at[1] = bed->has_center ? bed->center_y : (bed->min_y + bed->max_y) / 2.0;
	for (int k = 0; k < 2; k++) {
		/* Whole nanometres, so the 2-D work can move the sections exactly. */
		offset[k] = round((at[k] - (lo[k] + hi[k]) / 2.0) * SLICE_UNITS_PER_MM) /
			    SLICE_UNITS_PER_MM;
	}
	offset[2] = 0.0 - lo[2]; /* +0 rather than -0 for a mesh on z = 0 */
	for (int k = 0; k < 3; k++) {
		size[k] = hi[k] - lo[k];
		placed_lo[k] = lo[k] + offset[k];
		placed_hi[k] = hi[k] + offset[k];
		if (min)
			min[k] = placed_lo[k];
		if (max)
			max[k] = placed_hi[k];
	}
	if (size[2] > bed->max_height + SLICER_FIT_SLACK)
		return st_error_set(err, ST_ERR_RANGE,
				    "the model is %.2f mm tall but the printer builds at most "
				    "%.2f mm (max_print_height); scale it down or lay it on its side",
				    size[2], bed->max_height);
	if (placed_lo[0] < bed->min_x - SLICER_FIT_SLACK ||
	    placed_hi[0] > bed->max_x + SLICER_FIT_SLACK ||
	    placed_lo[1] < bed->min_y - SLICER_FIT_SLACK ||
	    placed_hi[1] > bed->max_y + SLICER_FIT_SLACK) {
		if (size[0] > bed->max_x - bed->min_x + SLICER_FIT_SLACK ||
		    size[1] > bed->max_y - bed->min_y + SLICER_FIT_SLACK)
			return st_error_set(err, ST_ERR_RANGE,
					    "the model is %.2f x %.2f mm but the bed is %.2f x %.2f mm "
					    "(bed_shape); scale it down or turn it",
					    size[0], size[1], bed->max_x - bed->min_x,
					    bed->max_y - bed->min_y);
		return st_error_set(err, ST_ERR_RANGE,
				    "placed at %.2f,%.2f the %.2f x %.2f mm model spans X %.2f to "
				    "%.2f and Y %.2f to %.2f mm, beyond the bed (X %.2f to %.2f, "
				    "Y %.2f to %.2f mm); move the centre",
				    at[0], at[1], size[0], size[1], placed_lo[0], placed_hi[0],
				    placed_lo[1], placed_hi[1], bed->min_x, bed->max_x, bed->min_y,
				    bed->max_y);
	}
	return 0;
}

/* Report progress if the caller asked for it. */
static void progress(const struct slicer_config *c, const char *stage, double done)
{
	if (c->progress)
		c->progress(c->progress_ctx, stage, done);
}

/* done of n layers written: "slicing layer 12 of 80" (the one under way). */
static void progress_layer(const struct slicer_config *c, size_t done, size_t n)
{
	char stage[64];

	if (!c->progress)
		return;
	snprintf(stage, sizeof(stage), "slicing layer %zu of %zu", done < n ? done + 1 : n, n);
	c->progress(c->progress_ctx, stage, (double)done / (double)(n ? n : 1));
}

/* Move every section of st by (dx, dy) nm. */
static void move_sections(struct slice_stack *st, int64_t dx, int64_t dy)
{
	for (size_t i = 0; i < st->n; i++) {
		struct clip_paths *p = &st->layers[i].regions.paths;
		size_t npts = clip_paths_points(p);

		for (size_t k = 0; k < npts; k++) {
			p->xy[2 * k] += dx;
			p->xy[2 * k + 1] += dy;
		}
	}
}

/* ---------------------------------------------------------------------------
 * The layer pipeline.  Worker threads make the walls (perim_generate, in
 * chunks of SLICER_CHUNK_LAYERS layers, each chunk with its own seam memory
 * warmed up on the layer below it) and then plan each layer's infill
 * (infill_plan_layer).  The calling thread takes the layers bottom to top:
 * it emits the layer's infill (ordered from where the layer below ended),
 * merges skirt/brim, support, walls and infill, hands the layer to the
 * sink (the G-code writer, or a stack) and frees it, helping with the
 * workers' tasks while its next layer is not ready.  Chunks start only
 * within a window above the last layer taken, so memory holds a few
 * chunks of layers, not the whole print.  None of this depends on the
 * number of threads: the output is the same for any count.
 */

enum { L_WAIT, L_WALLS, L_PLANNING, L_PLANNED }; /* a layer's state */
enum { C_TODO, C_RUNNING, C_DONE };		 /* a chunk's state */

struct pipe {
	const struct slicer_config *c;
	const struct slice_stack *st;
	const struct infill_job *job;
	int64_t travel_inset;	    /* nm, routing boundary inside the surface */
	bool travel;		    /* make travel maps */
	size_t vase_from;	    /* first spiral vase layer (spiral.h); SIZE_MAX: none */
	size_t nchunks, window;	    /* window: layers that may start above taken */
	struct layer_paths *walls;  /* st->n: the walls stage's paths */
	struct clip_expolys *inner; /* st->n: the regions inside the walls */
	struct perim_thin *thin;    /* st->n: what the thin walls dropped or widened */
	struct travel_map **maps;   /* st->n: travel maps, or NULL */
	struct infill_plan **plans; /* st->n */
	unsigned char *lstate;	    /* st->n layer states */
	unsigned char *cstate;	    /* nchunks chunk states */
	size_t taken;		    /* layers the calling thread has taken */
	pthread_mutex_t lock;	    /* guards the states, taken, rc and err */
	pthread_cond_t cond;	    /* signalled when a state changes */
	int rc;			    /* first error of a task */
	struct st_error err;	    /* its message */
};

/* A task: walls of a chunk (layer == SIZE_MAX) or the infill plan of a layer. */
struct task {
	size_t chunk, layer;
};

/* Mark layer i's walls made (lock held by the caller or not, see callers). */
static void walls_made(struct pipe *p, size_t i)
{
	pthread_mutex_lock(&p->lock);
	p->lstate[i] = L_WALLS;
	pthread_cond_broadcast(&p->cond);
	pthread_mutex_unlock(&p->lock);
}

/*
 * Walls of chunk k.  The seam memory starts on the layer below the chunk
 * (walls made and dropped), so seams continue across chunk boundaries the
 * same way whatever thread runs which chunk.
 */
static int walls_chunk(struct pipe *p, size_t k, struct st_error *err)
{
	struct perim_settings first_walls; /* layer 0's (slicer_first_layer_walls) */
	const struct perim_settings *ps;
	size_t first = k * SLICER_CHUNK_LAYERS;
	size_t last = first + SLICER_CHUNK_LAYERS < p->st->n ? first + SLICER_CHUNK_LAYERS
							      : p->st->n;
	struct perim_seams *seams = perim_seams_new((unsigned)k + 1u);
	int rc = 0;

	if (!seams)
		return st_error_set(err, ST_ERR_NOMEM, "walls: out of memory for seams");
	slicer_first_layer_walls(p->c, &first_walls);
	if (first > 0) {
		const struct slice_layer *below = &p->st->layers[first - 1];
		struct layer_paths scratch = {0};
		struct clip_expolys scratch_inner = {0};

		/* first > 0: never layer 0 */
		rc = perim_generate(&p->c->perim, &below->regions, below->height, seams, &scratch,
				    &scratch_inner, NULL, err);
		layer_paths_clear(&scratch);
		clip_expolys_free(&scratch_inner);
	}
	for (size_t i = first; i < last && !rc; i++) {
		const struct slice_layer *l = &p->st->layers[i];

		ps = i == 0 ? &first_walls : &p->c->perim;
		rc = perim_generate(ps, &l->regions, l->height, seams, &p->walls[i], &p->inner[i],
				    &p->thin[i], err);
		if (!rc && i >= p->vase_from) /* spiral vase: no infill above the bottom */
			clip_expolys_clear(&p->inner[i]);
		if (!rc && p->c->overhangs && i > 0 && i < p->vase_from) {
			struct overhang_settings os = {p->c->perim.nozzle_diameter,
						       p->c->infill.thick_bridges,
						       p->c->infill.bridge_flow_ratio};
			rc = overhang_split(&p->walls[i], &l->regions.paths,
					    &p->st->layers[i - 1].regions.paths, &os, err);
		}
		if (!rc && p->travel &&
		    !(p->maps[i] = travel_map_new(&l->regions, p->travel_inset, err)))
			rc = err->code;
		if (!rc && p->maps[i])
			travel_map_set_detour(p->maps[i], p->c->max_detour,
					      p->c->max_detour_is_percent);
		if (!rc)
			walls_made(p, i);
	}
	perim_seams_free(seams);
	return rc;
}

/* Run task t; on failure record the first error. */
static void run_task(struct pipe *p, struct task t)
{
	struct st_error err = {0};
	int rc;

	if (t.layer == SIZE_MAX)
		rc = walls_chunk(p, t.chunk, &err);
	else
		rc = infill_plan_layer(p->job, t.layer, &p->inner[t.layer], &p->plans[t.layer], &err);
	pthread_mutex_lock(&p->lock);
	if (t.layer == SIZE_MAX)
		p->cstate[t.chunk] = C_DONE;
	else
		p->lstate[t.layer] = L_PLANNED;
	if (rc && !p->rc) {
		p->rc = rc;
		p->err = err;
	}
	pthread_cond_broadcast(&p->cond);
	pthread_mutex_unlock(&p->lock);
}

/*
 * With the lock held: claim the next task, preferring the infill plan of
 * layer want when its walls are made, then the lowest chunk within the
 * window (walls are the long tasks the plans wait for), then the lowest
 * layer with walls and no plan.  False when there is none now.
 */
static bool claim_task(struct pipe *p, size_t want, struct task *t)
{
	size_t n = p->st->n;

	if (want < n && p->lstate[want] == L_WALLS) {
		*t = (struct task){.layer = want};
		p->lstate[want] = L_PLANNING;
		return true;
	}
	for (size_t k = 0; k < p->nchunks; k++) {
		if (p->cstate[k] != C_TODO)
			continue;
		if (k * SLICER_CHUNK_LAYERS >= p->taken + p->window)
			break;
		*t = (struct task){.chunk = k, .layer = SIZE_MAX};
		p->cstate[k] = C_RUNNING;
		return true;
	}
	for (size_t i = p->taken; i < n; i++)
		if (p->lstate[i] == L_WALLS) {
			*t = (struct task){.layer = i};
			p->lstate[i] = L_PLANNING;
			return true;
		}
	return false;
}

/* With the lock held: whether every layer has its plan claimed or made. */
static bool all_claimed(const struct pipe *p)
{
	for (size_t i = p->taken; i < p->st->n; i++)
		if (p->lstate[i] < L_PLANNING)
			return false;
	return true;
}

/* Worker thread: run tasks until all are claimed or one failed. */
static void *pipe_worker(void *arg)
{
	struct pipe *p = arg;
	struct task t;

	pthread_mutex_lock(&p->lock);
	while (!p->rc && !all_claimed(p)) {
		if (!claim_task(p, SIZE_MAX, &t)) {
			pthread_cond_wait(&p->cond, &p->lock);
			continue;
		}
		pthread_mutex_unlock(&p->lock);
		run_task(p, t);
		pthread_mutex_lock(&p->lock);
	}
	pthread_mutex_unlock(&p->lock);
	return NULL;
}

/* Worker threads to use: the setting or all cores, at least one. */
static size_t worker_count(int threads)
{
	long n = threads > 0 ? threads : sysconf(_SC_NPROCESSORS_ONLN);

	return n < 1 ? 1 : (size_t)n;
}

/* Move the paths of src to the end of dst's. */
static int move_paths(struct layer_paths *dst, struct layer_paths *src, size_t li,
		      struct st_error *err)
{
	struct toolpath *grown;

	if (!src->n)
		return 0;
	grown = slice_grow(dst->paths, &dst->cap, dst->n + src->n, sizeof(*grown));
	if (!grown)
		return st_error_set(err, ST_ERR_NOMEM, "slicer: out of memory merging layer %zu",
				    li + 1);
	dst->paths = grown;
	memcpy(dst->paths + dst->n, src->paths, src->n * sizeof(*src->paths));
	dst->n += src->n;
	src->n = 0; /* the points now belong to dst */
	return 0;
}

/* Where finished layers go: moved into stack, or written with w. */
struct sink {
	struct layer_stack *stack; /* slicer_toolpaths */
	const struct gcodew_settings *gs; /* slicer_run: the writer's settings, */
	const char *path;	   /* the file, */
	struct gcodew *w;	   /* the writer once begun */
	int rc;			   /* the writer's first error: reported after any
				    * of the stages', as when writing came last */
	struct st_error err;
	size_t base;		   /* layers before the part's (the raft) */
};

/* Hand the merged layer li to the sink; the sink takes or frees its paths. */
static int sink_layer(struct sink *k, struct layer_paths *m, size_t li)
{
	if (k->stack) {
		struct layer_paths *d = &k->stack->layers[li];
		*d = *m;
		*m = (struct layer_paths){.z = d->z, .height = d->height};
		return 0;
	}
	if (k->w && !k->rc) /* after an error nothing more is written; the stages go on */
		k->rc = gcodew_layer(k->w, m, &k->err);
	layer_paths_clear(m);
	return 0;
}

/* What the pipeline found, for the summary. */
struct pipe_result {
	size_t paths[PATH_ROLES];
	bool any, infill;
	struct slicer_thin thin;
};

/* Add layer number layer's (1-based, raft included) thin-wall counts to t. */
static void thin_add(struct slicer_thin *t, const struct perim_thin *l, size_t layer)
{
	t->dropped += l->dropped;
	if (!l->widened)
		return;
	if (!t->widened_layers++)
		t->first = layer;
	t->last = layer;
	if (!t->designed || l->designed < t->designed) {
		t->designed = l->designed;
		t->printed = l->printed;
	}
}

/*
 * Layer li, ready: emit its infill, merge the stages in the order
 * skirt/brim, support, walls, infill, count its paths and sink it.
 */
static int finish_layer(struct pipe *p, struct infill_job *job, struct layer_stack *skirt,
			struct layer_stack *support, size_t li, struct sink *k,
			struct pipe_result *res, struct st_error *err)
{
	struct layer_paths m = {.z = p->st->layers[li].z, .height = p->st->layers[li].height};
	size_t walls_end;
	int rc = move_paths(&m, &skirt->layers[li], li, err);

	if (!rc)
		rc = move_paths(&m, &support->layers[li], li, err);
	if (!rc)
		rc = move_paths(&m, &p->walls[li], li, err);
	walls_end = m.n;
	if (!rc)
		rc = infill_emit_layer(job, p->plans[li], &m, err);
	if (rc) {
		layer_paths_clear(&m);
		return rc;
	}
	res->infill = res->infill || m.n > walls_end;
	thin_add(&res->thin, &p->thin[li], k->base + li + 1);
	m.spiral = li >= p->vase_from && spiral_layer_fits(&m);
	for (size_t i = 0; i < m.n; i++)
		res->paths[m.paths[i].role]++;
	res->any = res->any || m.n;
	m.travel = p->maps[li];
	p->maps[li] = NULL;
	return sink_layer(k, &m, k->base + li);
}

/*
 * The raft's layers, skirt/brim then raft paths (whose paths are taken),
 * counted and sunk below the part's.
 */
static int sink_raft(const struct slice_stack *raft, struct layer_stack *skirt,
		     struct layer_stack *paths, struct sink *k, struct pipe_result *res,
		     struct st_error *err)
{
	int rc = 0;

	for (size_t i = 0; i < raft->n && !rc; i++) {
		struct layer_paths m = {.z = raft->layers[i].z, .height = raft->layers[i].height};

		rc = move_paths(&m, &skirt->layers[i], i, err);
		if (!rc)
			rc = move_paths(&m, &paths->layers[i], i, err);
		if (rc) {
			layer_paths_clear(&m);
			break;
		}
		for (size_t j = 0; j < m.n; j++)
			res->paths[m.paths[j].role]++;
		res->any = res->any || m.n;
		rc = sink_layer(k, &m, i);
	}
	return rc;
}

/* Free what the pipeline holds for layer i. */
static void drop_layer(struct pipe *p, size_t i)
{
	layer_paths_clear(&p->walls[i]);
	clip_expolys_free(&p->inner[i]);
	travel_map_free(p->maps[i]);
	p->maps[i] = NULL;
	infill_plan_free(p->plans[i]);
	p->plans[i] = NULL;
}

/*
 * Walls and infill of every layer, merged with the skirt and support
 * stacks (whose paths are taken), into the sink bottom to top.
 */
static int run_pipe(const struct slicer_config *c, const struct slice_stack *st,
		    size_t vase_from, struct layer_stack *skirt, struct layer_stack *support,
		    struct sink *k, struct pipe_result *res, struct st_error *err)
{
	struct pipe p = {.c = c, .st = st, .travel = c->gcodew.avoid_crossing_perimeters,
			 .vase_from = vase_from};
	struct infill_job *job = NULL;
	pthread_t tid[SLICER_MAX_THREADS];
	size_t nworkers = worker_count(c->threads), started = 0, n = st->n;
	/* PrusaSlicer's routing boundary: 1.5 perimeter spacings inside, so
	 * routes run over the inner walls, never over the outer face. */
	double spacing = perim_spacing(c->perim.extrusion_width, c->layer_height);
	int rc;

	p.travel_inset = llround(1.5 * spacing * SLICE_UNITS_PER_MM);
	if (p.travel_inset < 1)
		p.travel_inset = 1;
	p.nchunks = (n + SLICER_CHUNK_LAYERS - 1) / SLICER_CHUNK_LAYERS;
	p.window = (nworkers + 1) * SLICER_CHUNK_LAYERS;
	rc = stage_infill_job(c, st, &job, err);
	if (rc)
		return rc;
	p.job = job;
	p.walls = calloc(n, sizeof(*p.walls));
	p.inner = calloc(n, sizeof(*p.inner));
	p.thin = calloc(n ? n : 1, sizeof(*p.thin));
	p.maps = calloc(n, sizeof(*p.maps));
	p.plans = calloc(n, sizeof(*p.plans));
	p.lstate = calloc(n, sizeof(*p.lstate));
	p.cstate = calloc(p.nchunks ? p.nchunks : 1, sizeof(*p.cstate));
	if (!p.walls || !p.inner || !p.thin || !p.maps || !p.plans || !p.lstate || !p.cstate) {
		rc = st_error_set(err, ST_ERR_NOMEM, "slicer: out of memory for %zu layers", n);
		goto out_free;
	}
	for (size_t i = 0; i < n; i++) {
		p.walls[i].z = st->layers[i].z;
		p.walls[i].height = st->layers[i].height;
	}
	if (pthread_mutex_init(&p.lock, NULL)) {
		rc = st_error_set(err, ST_ERR_INTERNAL, "slicer: cannot create a mutex");
		goto out_free;
	}
	if (pthread_cond_init(&p.cond, NULL)) {
		pthread_mutex_destroy(&p.lock);
		rc = st_error_set(err, ST_ERR_INTERNAL, "slicer: cannot create a condition");
		goto out_free;
	}
	progress_layer(c, 0, n);
	/* The calling thread is one worker; a thread that cannot start is
	 * only a lost core, the tasks are shared by those that run. */
	for (size_t t = 1; t < nworkers && t < SLICER_MAX_THREADS; t++) {
		if (pthread_create(&tid[started], NULL, pipe_worker, &p))
			break;
		started++;
	}
	for (size_t i = 0; i < n && !rc; i++) {
		struct task t;

		pthread_mutex_lock(&p.lock);
		while (!p.rc && p.lstate[i] != L_PLANNED) {
			if (claim_task(&p, i, &t)) {
				pthread_mutex_unlock(&p.lock);
				run_task(&p, t);
				pthread_mutex_lock(&p.lock);
			} else {
				pthread_cond_wait(&p.cond, &p.lock);
			}
		}
		if (p.rc) {
			rc = p.rc;
			if (err)
				*err = p.err;
		}
		pthread_mutex_unlock(&p.lock);
		if (!rc)
			rc = finish_layer(&p, job, skirt, support, i, k, res, err);
		drop_layer(&p, i);
		pthread_mutex_lock(&p.lock);
		p.taken = i + 1;
		if (rc && !p.rc)
			p.rc = rc; /* the workers stop */
		pthread_cond_broadcast(&p.cond);
		pthread_mutex_unlock(&p.lock);
		if (!rc)
			progress_layer(c, i + 1, n);
	}
	for (size_t t = 0; t < started; t++)
		pthread_join(tid[t], NULL);
	pthread_cond_destroy(&p.cond);
	pthread_mutex_destroy(&p.lock);
out_free:
	for (size_t i = 0; p.walls && p.inner && p.maps && p.plans && i < n; i++)
		drop_layer(&p, i);
	free(p.walls);
	free(p.inner);
	free(p.thin);
	free(p.maps);
	free(p.plans);
	free(p.lstate);
	free(p.cstate);
	infill_job_free(job);
	return rc;
}

/*
 * Stages 1-4 into the sink: place, slice, the raft, support and
 * skirt/brim for the whole stack, then the raft's layers and the layer
 * pipeline.  Errors in the order the stages
 * come (the pipeline's before support's and skirt's, which are computed
 * first but reported as if they came after), then "nothing to print",
 * then the sink's.
 */
static int toolpaths(const struct mesh *m, const struct slicer_config *c,
		     struct layer_stack **shape, struct sink *k, struct slicer_summary *sum,
		     struct st_error *err)
{
	enum { SKIRT, SUPPORT, RAFT_SKIRT, RAFT, STAGES };
	struct slicer_summary s = {0};
	struct slicer_config vase;
	size_t vase_from = SIZE_MAX;
	struct slice_stack *st = NULL, *raft = NULL;
	struct layer_stack *stage[STAGES] = {0};
	struct pipe_result res = {.any = false};
	struct st_error late_err = {0};
	bool ran[STAGES] = {false};
	/* PrusaSlicer's first object layer over a raft is an ordinary layer. */
	double first = c->raft.layers > 0 ? c->layer_height : c->first_layer_height, lift = 0.0;
	int rc, late = 0;

	rc = slicer_config_check(c, err);
	if (!rc)
		rc = slicer_place(m, &c->bed, s.offset, s.min, s.max, err);
	if (rc)
		return rc;
	if (c->gcodew.spiral_vase) {
		vase = *c;
		slicer_config_modes(&vase);
		c = &vase;
	}

	progress(c, "cutting the model into layers", 0.0);
	rc = stage_slice(m, c, &st, &s, err);
	if (rc)
		return rc;
	progress(c, "cutting the model into layers", 1.0);
	if (st->n == 0) {
		rc = st_error_set(err, ST_ERR_RANGE,
				  "the model is %.3g mm tall, less than half the first layer "
				  "(%g mm): there is nothing to slice",
				  s.max[2] - s.min[2], first);
		goto out_free;
	}
	move_sections(st, llround(s.offset[0] * SLICE_UNITS_PER_MM),
		      llround(s.offset[1] * SLICE_UNITS_PER_MM));
	for (size_t i = 0; i < st->n && !rc; i++) {
		s.open_dropped += st->layers[i].open_dropped;
		rc = clip_expolys_clean(&st->layers[i].regions, SLICER_CLEAN_NM, err);
	}
	if (!rc && c->elefant_foot_compensation > 0 && c->raft.layers == 0)
		rc = slice_layer_shrink(&st->layers[0], c->elefant_foot_compensation,
					SLICER_CLEAN_NM, err);
	if (!rc && c->raft.layers > 0)
		rc = stage_raft_layers(c, st, &raft, &lift, err);
	if (!rc && c->gcodew.spiral_vase)
		vase_from = spiral_first_layer(st, c->infill.bottom_solid_layers,
					       c->infill.bottom_solid_min_thickness);
	for (size_t i = vase_from; !rc && i < st->n; i++)
		rc = spiral_keep_outline(&st->layers[i], err);
	if (!rc)
		rc = stage_report_plan(c, raft, st, err);
	if (rc)
		goto out_free;
	if (shape && !(*shape = stage_print_stack(raft, st, err))) {
		rc = ST_ERR_NOMEM;
		goto out_free;
	}
	if (shape)
		k->stack = *shape;
	k->base = raft ? raft->n : 0;
	if (k->path) /* its errors wait until the stages have succeeded */
		k->rc = gcodew_begin_file(k->gs, k->base + st->n, k->path, &k->w, &k->err);
	for (int j = 0; j < STAGES; j++)
		if ((j < RAFT_SKIRT || raft) &&
		    !(stage[j] = stage_stack(j < RAFT_SKIRT ? st : raft, err))) {
			rc = ST_ERR_NOMEM;
			goto out_free;
		}

	late = stage_support(c, st, stage[SUPPORT], &ran[SUPPORT], &late_err);
	if (raft) {
		rc = stage_raft(c, st, ran[SUPPORT] ? stage[SUPPORT] : NULL, raft, stage[RAFT], err);
		if (rc)
			goto out_free;
	}
	/* The skirt and brim go around the raft when there is one. */
	if (!late && raft)
		late = stage_skirt(c, raft, NULL, stage[RAFT_SKIRT], &ran[SKIRT], &late_err);
	else if (!late)
		late = stage_skirt(c, st, ran[SUPPORT] ? stage[SUPPORT] : NULL, stage[SKIRT],
				   &ran[SKIRT], &late_err);
	if (raft)
		rc = sink_raft(raft, stage[RAFT_SKIRT], stage[RAFT], k, &res, err);
	if (!rc)
		rc = run_pipe(c, st, vase_from, stage[SKIRT], stage[SUPPORT], k, &res, err);
	if (!rc && late) {
		rc = late;
		if (err)
			*err = late_err;
	}
	if (rc)
		goto out_free;
	if (!res.any) {
		rc = st_error_set(err, ST_ERR_RANGE,
				  "no layer has anything to print: every feature of the model is "
				  "narrower than min_feature_size (%g mm)",
				  c->perim.min_feature_size);
		goto out_free;
	}
	memcpy(s.paths, res.paths, sizeof(s.paths));
	s.thin = res.thin;
	s.layers = k->base + st->n;
	s.raft_layers = k->base;
	s.offset[2] += lift;
	s.min[2] += lift;
	s.max[2] += lift;
	s.walls = true;
	s.infill = res.infill;
	s.support = ran[SUPPORT];
	s.skirt = ran[SKIRT];
	if (sum)
		*sum = s;

out_free:
	for (int j = 0; j < STAGES; j++)
		layer_stack_free(stage[j]);
	slice_stack_free(raft);
	slice_stack_free(st);
	return rc;
}

int slicer_toolpaths(const struct mesh *m, const struct slicer_config *c,
		     struct layer_stack **out, struct slicer_summary *sum, struct st_error *err)
{
	struct sink k = {0};
	int rc;

	if (!out)
		return st_error_set(err, ST_ERR_ARG, "slicer: slicer_toolpaths needs an out pointer");
	*out = NULL;
	rc = toolpaths(m, c, out, &k, sum, err);
	if (rc) {
		layer_stack_free(*out);
		*out = NULL;
	}
	return rc;
}

int slicer_run(const struct mesh *m, const struct slicer_config *c, const char *path,
	       struct slicer_summary *sum, struct st_error *err)
{
	struct slicer_summary s;
	struct gcodew_settings gs;
	struct gcodew_summary gsum;
	struct sink k = {.gs = &gs, .path = path};
	char block[2048];
	int rc;

	if (!path || !*path)
		return st_error_set(err, ST_ERR_ARG, "slicer: no output file given");
	if (!c)
		return slicer_config_check(c, err);
	gs = c->gcodew;
	if (slicer_settings_text(c, block, sizeof(block)) < sizeof(block))
		gs.slicer_block = block;
	gs.nozzle_diameter = c->perim.nozzle_diameter;
	gs.layer_height = c->layer_height;
	gs.first_layer_height = c->first_layer_height;
	gs.raft_layers = c->raft.layers;
	gs.raft_contact_distance = c->raft.contact_distance;
	gs.raft_expansion = c->raft.expansion;
	gs.raft_first_layer_density = c->raft.first_layer_density;
	gs.raft_first_layer_expansion = c->raft.first_layer_expansion;
	rc = toolpaths(m, c, NULL, &k, &s, err);
	if (!rc && k.rc) {
		rc = k.rc;
		if (err)
			*err = k.err;
	}
	if (!rc) {
		progress(c, "writing the G-code", 0.0);
		rc = gcodew_finish_file(k.w, &gsum, err);
	}
	gcodew_free(k.w);
	if (rc)
		return rc;
	progress(c, "writing the G-code", 1.0);
	s.layers = gsum.layers;
	s.time_s = gsum.time_s;
	s.filament_mm = gsum.filament_mm;
	s.filament_cm3 = gsum.filament_cm3;
	s.filament_g = gsum.filament_g;
	s.moves = gsum.moves;
	if (sum)
		*sum = s;
	return 0;
}
