/*
 * slicer.c - the slicing job: place, slice, run the stages into their own
 * layer stacks, merge them per layer, write G-code (see slicer.h).
 */
#include "slicer.h"

#include <math.h>
#include <pthread.h>
#include <stdlib.h>
#include <string.h>
#include <unistd.h>

#include "grow.h"
#include "infill.h"
#include "skirt.h"
#include "support.h"
#include "travel.h"

void slicer_config_init(struct slicer_config *c, double nozzle_diameter)
{
	memset(c, 0, sizeof(*c));
	c->layer_height = 0.2;
	c->first_layer_height = 0.2;
	slice_settings_init(&c->slice);
	c->slice.nozzle_diameter = nozzle_diameter;
	perim_settings_init(&c->perim, nozzle_diameter);
	gcodew_settings_init(&c->gcodew);
	c->gcodew.nozzle_diameter = nozzle_diameter;
	c->infill = (struct slicer_infill_settings){
	    .density = 20, .pattern = "rectilinear", .top_solid_layers = 3, .bottom_solid_layers = 3};
	c->support = (struct slicer_support_settings){.enabled = false, .threshold = 0};
	c->skirt = (struct slicer_skirt_settings){.skirts = 1, .brim_width = 0};
	c->bed = (struct slicer_bed){.max_x = 200, .max_y = 200, .max_height = 200};
}

int slicer_config_check(const struct slicer_config *c, struct st_error *err)
{
	int rc;

	if (!c)
		return st_error_set(err, ST_ERR_ARG, "slicer: no settings given");
	if (c->slice.nozzle_diameter != c->perim.nozzle_diameter)
		return st_error_set(err, ST_ERR_ARG,
				    "slicer: the slicing nozzle %g mm and the walls' nozzle %g mm "
				    "differ; set both from nozzle_diameter",
				    c->slice.nozzle_diameter, c->perim.nozzle_diameter);
	rc = slice_settings_check(&c->slice, c->first_layer_height, c->layer_height, err);
	if (!rc)
		rc = perim_settings_check(&c->perim, c->first_layer_height, err);
	if (!rc)
		rc = perim_settings_check(&c->perim, c->layer_height, err);
	if (rc)
		return rc;
	if (!(c->infill.density >= 0.0 && c->infill.density <= 100.0))
		return st_error_set(err, ST_ERR_RANGE,
				    "fill_density = %g%% is out of range; use 0 to 100%%",
				    c->infill.density);
	if (!c->infill.pattern)
		return st_error_set(err, ST_ERR_ARG, "slicer: no fill_pattern given");
	enum infill_pattern pattern;
	rc = infill_pattern_parse(c->infill.pattern, &pattern, err);
	if (rc)
		return rc; /* before any slicing: a pattern we cannot print */
	if (c->infill.top_solid_layers < 0 || c->infill.bottom_solid_layers < 0)
		return st_error_set(err, ST_ERR_RANGE,
				    "top_solid_layers = %d, bottom_solid_layers = %d: layer counts "
				    "cannot be negative; use 0 or more",
				    c->infill.top_solid_layers, c->infill.bottom_solid_layers);
	if (c->support.threshold < 0 || c->support.threshold > 90)
		return st_error_set(err, ST_ERR_RANGE,
				    "support_material_threshold = %d is out of range; use 0 "
				    "(automatic) to 90 degrees",
				    c->support.threshold);
	if (c->skirt.skirts < 0)
		return st_error_set(err, ST_ERR_RANGE,
				    "skirts = %d: the loop count cannot be negative; use 0 or more",
				    c->skirt.skirts);
	if (!(c->skirt.brim_width >= 0.0 && c->skirt.brim_width <= 1000.0))
		return st_error_set(err, ST_ERR_RANGE,
				    "brim_width = %g mm is out of range; use 0 to 1000 mm",
				    c->skirt.brim_width);
	if (!(c->bed.max_x > c->bed.min_x && c->bed.max_y > c->bed.min_y &&
	      c->bed.max_height > 0.0 && isfinite(c->bed.max_x - c->bed.min_x) &&
	      isfinite(c->bed.max_y - c->bed.min_y) && isfinite(c->bed.max_height)))
		return st_error_set(err, ST_ERR_RANGE,
				    "the bed (%g to %g mm in X, %g to %g mm in Y, %g mm high) is "
				    "empty; check bed_shape and max_print_height",
				    c->bed.min_x, c->bed.max_x, c->bed.min_y, c->bed.max_y,
				    c->bed.max_height);
	if (c->bed.has_center && !(isfinite(c->bed.center_x) && isfinite(c->bed.center_y)))
		return st_error_set(err, ST_ERR_RANGE, "the placement centre is not a finite point");
	if (c->threads < 0 || c->threads > SLICER_MAX_THREADS)
		return st_error_set(err, ST_ERR_RANGE,
				    "threads = %d is out of range; use 0 (all cores) to %d",
				    c->threads, SLICER_MAX_THREADS);
	return 0;
}

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

/* An empty stack with the layers (z, height) of the sections. */
static struct layer_stack *stage_stack_new(const struct slice_stack *st, struct st_error *err)
{
	struct layer_stack *s = layer_stack_new(st->n, err);

	if (s)
		for (size_t i = 0; i < st->n; i++) {
			s->layers[i].z = st->layers[i].z;
			s->layers[i].height = st->layers[i].height;
		}
	return s;
}

/* ---------------------------------------------------------------------------
 * Walls: perim_generate per layer, in parallel over chunks of layers.
 */

struct walls_job {
	const struct slicer_config *c;
	const struct slice_stack *st;
	struct layer_stack *out;
	struct clip_expolys *inner; /* st->n regions inside the walls */
	struct travel_map **travel; /* st->n travel maps, NULL when travels go straight */
	int64_t travel_inset;	    /* nm, routing boundary inside the surface */
	size_t nchunks, next, done;
	pthread_mutex_t lock;
	int rc;			/* first error */
	struct st_error err;	/* its message */
};

/*
 * Walls of chunk k.  The seam memory starts on the layer below the chunk
 * (walls made and dropped), so seams continue across chunk boundaries the
 * same way whatever thread runs which chunk.
 */
static int walls_chunk(struct walls_job *j, size_t k, struct st_error *err)
{
	const struct perim_settings *ps = &j->c->perim;
	size_t first = k * SLICER_CHUNK_LAYERS;
	size_t last = first + SLICER_CHUNK_LAYERS < j->st->n ? first + SLICER_CHUNK_LAYERS
							      : j->st->n;
	struct perim_seams *seams = perim_seams_new((unsigned)k + 1u);
	int rc = 0;

	if (!seams)
		return st_error_set(err, ST_ERR_NOMEM, "walls: out of memory for seams");
	if (first > 0) {
		const struct slice_layer *below = &j->st->layers[first - 1];
		struct layer_stack *scratch = layer_stack_new(1, err);
		struct clip_expolys scratch_inner = {0};

		rc = scratch ? perim_generate(ps, &below->regions, below->height, seams,
					      &scratch->layers[0], &scratch_inner, err)
			     : ST_ERR_NOMEM;
		layer_stack_free(scratch);
		clip_expolys_free(&scratch_inner);
	}
	for (size_t i = first; i < last && !rc; i++) {
		const struct slice_layer *l = &j->st->layers[i];

		rc = perim_generate(ps, &l->regions, l->height, seams, &j->out->layers[i],
				    &j->inner[i], err);
		if (!rc && j->travel && !(j->travel[i] = travel_map_new(&l->regions,
									j->travel_inset, err)))
			rc = err->code;
		if (!rc) {
			pthread_mutex_lock(&j->lock);
			j->done++;
			progress(j->c, "walls", (double)j->done / (double)j->st->n);
			pthread_mutex_unlock(&j->lock);
		}
	}
	perim_seams_free(seams);
	return rc;
}

/* Worker: take chunks until none is left or one failed. */
static void *walls_worker(void *arg)
{
	struct walls_job *j = arg;

	for (;;) {
		struct st_error err = {0};
		size_t k;
		int rc;

		pthread_mutex_lock(&j->lock);
		if (j->rc || j->next >= j->nchunks) {
			pthread_mutex_unlock(&j->lock);
			return NULL;
		}
		k = j->next++;
		pthread_mutex_unlock(&j->lock);
		rc = walls_chunk(j, k, &err);
		if (rc) {
			pthread_mutex_lock(&j->lock);
			if (!j->rc) {
				j->rc = rc;
				j->err = err;
			}
			pthread_mutex_unlock(&j->lock);
		}
	}
}

/* Worker threads to start: the setting or all cores, at most one per chunk. */
static size_t worker_count(int threads, size_t nchunks)
{
	long n = threads > 0 ? threads : sysconf(_SC_NPROCESSORS_ONLN);

	if (n < 1)
		n = 1;
	return (size_t)n < nchunks ? (size_t)n : nchunks;
}

/*
 * Stage "walls": outer and inner perimeters, gap fill and thin walls of
 * every layer into out, the region inside the walls of layer i into
 * inner[i] (what the infill stage fills), and when travel is not NULL the
 * travel map of layer i's region into travel[i].
 */
static int stage_walls(const struct slicer_config *c, const struct slice_stack *st,
		       struct clip_expolys *inner, struct travel_map **travel,
		       struct layer_stack *out, struct st_error *err)
{
	struct walls_job j = {.c = c, .st = st, .out = out, .inner = inner, .travel = travel};
	/* PrusaSlicer's routing boundary: 1.5 perimeter spacings inside, so
	 * routes run over the inner walls, never over the outer face. */
	double spacing = perim_spacing(c->perim.extrusion_width, c->layer_height);

	j.travel_inset = llround(1.5 * spacing * SLICE_UNITS_PER_MM);
	if (j.travel_inset < 1)
		j.travel_inset = 1;
	pthread_t tid[SLICER_MAX_THREADS];
	size_t nworkers, started = 0;

	j.nchunks = (st->n + SLICER_CHUNK_LAYERS - 1) / SLICER_CHUNK_LAYERS;
	if (!j.nchunks)
		return 0;
	if (pthread_mutex_init(&j.lock, NULL))
		return st_error_set(err, ST_ERR_INTERNAL, "walls: cannot create a mutex");
	progress(c, "walls", 0.0);
	nworkers = worker_count(c->threads, j.nchunks);
	/* The calling thread is one worker; a thread that cannot start is
	 * only a lost core, the chunks are shared by those that run. */
	for (size_t t = 1; t < nworkers; t++) {
		if (pthread_create(&tid[started], NULL, walls_worker, &j))
			break;
		started++;
	}
	walls_worker(&j);
	for (size_t t = 0; t < started; t++)
		pthread_join(tid[t], NULL);
	pthread_mutex_destroy(&j.lock);
	if (j.rc) {
		if (err)
			*err = j.err;
		return j.rc;
	}
	return 0;
}

/* Whether any layer of s holds a path. */
static bool stack_has_paths(const struct layer_stack *s)
{
	for (size_t l = 0; l < s->nlayers; l++)
		if (s->layers[l].n)
			return true;
	return false;
}

/*
 * Stage "infill" (infill.h): skins, bridges, solid and sparse infill in
 * inner[i], the region left inside layer i's walls, with the walls' width
 * and the job's flow.  Sets *ran when it produced paths.
 */
static int stage_infill(const struct slicer_config *c, const struct slice_stack *st,
			const struct clip_expolys *inner, struct layer_stack *out, bool *ran,
			struct st_error *err)
{
	struct infill_settings s;
	int rc;

	infill_settings_init(&s, c->perim.nozzle_diameter);
	rc = infill_pattern_parse(c->infill.pattern, &s.fill_pattern, err);
	if (rc)
		return rc;
	s.fill_density = c->infill.density;
	s.top_solid_layers = c->infill.top_solid_layers;
	s.bottom_solid_layers = c->infill.bottom_solid_layers;
	s.layer_height = c->layer_height;
	s.perimeter_extrusion_width = c->perim.extrusion_width;
	s.infill_extrusion_width = c->perim.extrusion_width;
	s.solid_infill_extrusion_width = c->perim.extrusion_width;
	s.top_infill_extrusion_width = c->perim.extrusion_width;
	rc = infill_generate(&s, st, inner, out, err);
	*ran = !rc && stack_has_paths(out);
	return rc;
}

/*
 * Stage "support" (support.h): support material under overhangs, from the
 * bed, when the job asks for it.  Sets *ran when it produced paths.
 */
static int stage_support(const struct slicer_config *c, const struct slice_stack *st,
			 struct layer_stack *out, bool *ran, struct st_error *err)
{
	struct support_settings s;
	int rc;

	*ran = false;
	if (!c->support.enabled)
		return 0;
	support_settings_init(&s, c->perim.nozzle_diameter);
	s.support_material = true;
	s.support_material_threshold = c->support.threshold;
	s.extrusion_width = c->perim.extrusion_width;
	rc = support_generate(&s, st, out, err);
	*ran = !rc && stack_has_paths(out);
	return rc;
}

/*
 * Stage "skirt/brim" (skirt.h), run after the support stage so the skirt
 * goes around the supports too.  Sets *ran when it produced paths.
 */
static int stage_skirt(const struct slicer_config *c, const struct slice_stack *st,
		       const struct layer_stack *support, struct layer_stack *out, bool *ran,
		       struct st_error *err)
{
	struct skirt_settings s;
	int rc;

	skirt_settings_init(&s, c->perim.nozzle_diameter);
	s.skirts = c->skirt.skirts;
	s.brim_width = c->skirt.brim_width;
	s.extrusion_width = c->perim.extrusion_width;
	s.filament_diameter = c->gcodew.filament_diameter;
	rc = skirt_generate(&s, st, support, out, err);
	*ran = !rc && stack_has_paths(out);
	return rc;
}

/* Move the paths of every layer of src to the end of dst's (same layers). */
static int merge_stage(struct layer_stack *dst, struct layer_stack *src, struct st_error *err)
{
	for (size_t i = 0; i < dst->nlayers; i++) {
		struct layer_paths *d = &dst->layers[i], *s = &src->layers[i];
		struct toolpath *grown;

		if (!s->n)
			continue;
		grown = slice_grow(d->paths, &d->cap, d->n + s->n, sizeof(*grown));
		if (!grown)
			return st_error_set(err, ST_ERR_NOMEM, "slicer: out of memory merging layer %zu",
					    i + 1);
		d->paths = grown;
		memcpy(d->paths + d->n, s->paths, s->n * sizeof(*s->paths));
		d->n += s->n;
		s->n = 0; /* the points now belong to dst */
	}
	return 0;
}

/* Count the paths per role and say whether any layer has a path. */
static bool count_paths(const struct layer_stack *s, size_t paths[PATH_ROLES])
{
	bool any = false;

	memset(paths, 0, PATH_ROLES * sizeof(*paths));
	for (size_t i = 0; i < s->nlayers; i++)
		for (size_t p = 0; p < s->layers[i].n; p++) {
			paths[s->layers[i].paths[p].role]++;
			any = true;
		}
	return any;
}

int slicer_toolpaths(const struct mesh *m, const struct slicer_config *c,
		     struct layer_stack **out, struct slicer_summary *sum, struct st_error *err)
{
	enum { SKIRT, SUPPORT, WALLS, INFILL, STAGES };
	struct slicer_summary s = {0};
	struct slice_stack *st = NULL;
	struct layer_stack *stage[STAGES] = {0}, *merged = NULL;
	struct clip_expolys *inner = NULL;
	struct travel_map **travel = NULL;
	bool ran[STAGES] = {false};
	int rc;

	if (!out)
		return st_error_set(err, ST_ERR_ARG, "slicer: slicer_toolpaths needs an out pointer");
	*out = NULL;
	rc = slicer_config_check(c, err);
	if (!rc)
		rc = slicer_place(m, &c->bed, s.offset, s.min, s.max, err);
	if (rc)
		return rc;

	progress(c, "slicing", 0.0);
	rc = slice_mesh(m, c->first_layer_height, c->layer_height, &c->slice, &st, err);
	if (rc)
		return rc;
	progress(c, "slicing", 1.0);
	if (st->n == 0) {
		rc = st_error_set(err, ST_ERR_RANGE,
				  "the model is %.3g mm tall, less than half the first layer "
				  "(%g mm): there is nothing to slice",
				  s.max[2] - s.min[2], c->first_layer_height);
		goto out_free;
	}
	move_sections(st, llround(s.offset[0] * SLICE_UNITS_PER_MM),
		      llround(s.offset[1] * SLICE_UNITS_PER_MM));
	for (size_t i = 0; i < st->n; i++)
		s.open_dropped += st->layers[i].open_dropped;

	inner = calloc(st->n, sizeof(*inner));
	if (c->gcodew.avoid_crossing_perimeters)
		travel = calloc(st->n, sizeof(*travel));
	merged = stage_stack_new(st, err);
	for (int k = 0; k < STAGES; k++)
		stage[k] = stage_stack_new(st, err);
	if (!inner || (c->gcodew.avoid_crossing_perimeters && !travel) || !merged ||
	    !stage[SKIRT] || !stage[SUPPORT] || !stage[WALLS] || !stage[INFILL]) {
		rc = st_error_set(err, ST_ERR_NOMEM, "slicer: out of memory for %zu layers", st->n);
		goto out_free;
	}

	rc = stage_walls(c, st, inner, travel, stage[WALLS], err);
	ran[WALLS] = true;
	if (!rc)
		rc = stage_infill(c, st, inner, stage[INFILL], &ran[INFILL], err);
	if (!rc)
		rc = stage_support(c, st, stage[SUPPORT], &ran[SUPPORT], err);
	if (!rc)
		rc = stage_skirt(c, st, ran[SUPPORT] ? stage[SUPPORT] : NULL, stage[SKIRT],
				 &ran[SKIRT], err);
	for (int k = 0; k < STAGES && !rc; k++) /* skirt/brim, support, walls, infill */
		rc = merge_stage(merged, stage[k], err);
	if (rc)
		goto out_free;
	for (size_t i = 0; travel && i < st->n; i++) {
		merged->layers[i].travel = travel[i];
		travel[i] = NULL;
	}
	if (!count_paths(merged, s.paths)) {
		rc = st_error_set(err, ST_ERR_RANGE,
				  "no layer has anything to print: every feature of the model is "
				  "narrower than the nozzle (%g mm)",
				  c->perim.nozzle_diameter);
		goto out_free;
	}
	s.layers = merged->nlayers;
	s.walls = ran[WALLS];
	s.infill = ran[INFILL];
	s.support = ran[SUPPORT];
	s.skirt = ran[SKIRT];
	if (sum)
		*sum = s;
	*out = merged;
	merged = NULL;

out_free:
	layer_stack_free(merged);
	for (int k = 0; k < STAGES; k++)
		layer_stack_free(stage[k]);
	if (inner)
		for (size_t i = 0; i < st->n; i++)
			clip_expolys_free(&inner[i]);
	free(inner);
	if (travel)
		for (size_t i = 0; i < st->n; i++)
			travel_map_free(travel[i]);
	free(travel);
	slice_stack_free(st);
	return rc;
}

int slicer_run(const struct mesh *m, const struct slicer_config *c, const char *path,
	       struct slicer_summary *sum, struct st_error *err)
{
	struct layer_stack *stack = NULL;
	struct slicer_summary s;
	struct gcodew_settings gs;
	struct gcodew_summary gsum;
	int rc;

	if (!path || !*path)
		return st_error_set(err, ST_ERR_ARG, "slicer: no output file given");
	rc = slicer_toolpaths(m, c, &stack, &s, err);
	if (rc)
		return rc;
	gs = c->gcodew;
	gs.nozzle_diameter = c->perim.nozzle_diameter;
	gs.layer_height = c->layer_height;
	gs.first_layer_height = c->first_layer_height;
	progress(c, "writing G-code", 0.0);
	rc = gcodew_write_file(stack, &gs, path, &gsum, err);
	layer_stack_free(stack);
	if (rc)
		return rc;
	progress(c, "writing G-code", 1.0);
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
