/*
 * threemf.c - 3MF input (docs/repair.md "3MF"): open the zip with libzip,
 * find the model part through _rels/.rels, stream it (and the parts its
 * p:path references name) to the parser of threemf_xml.c, then place every
 * build item: each object's triangles through the item's and its
 * components' transforms, in the model's unit, into one mesh.
 *
 * Untrusted input: every entry is decompressed as a stream and all of them
 * together may unpack to at most TMF_UNPACK_MAX bytes (a zip bomb stops
 * there), components may nest TMF_NESTING_MAX deep and not in a cycle, and
 * the build may place at most TMF_PLACED_MAX triangles (components can
 * repeat one mesh many times over).
 */
#include "threemf_impl.h"
#include "st_grow.h"

#include <math.h>
#include <stdlib.h>
#include <string.h>
#include <zip.h>

/* All entries of one file together unpack to at most this many bytes. */
#define TMF_UNPACK_MAX (2ull << 30)
/* Components inside components inside ... at most this deep. */
#define TMF_NESTING_MAX 64
/* Triangles the build may place (134 million, 6.7 GB as binary STL). */
#define TMF_PLACED_MAX (1ull << 27)
/* A metadata entry (the slicer configuration, a layer height profile) may
 * unpack to at most this many bytes. */
#define TMF_CONFIG_MAX (16u << 20)
/* The model part when there is no _rels/.rels, and the rels part. */
#define TMF_DEFAULT_MODEL "3D/3dmodel.model"
#define TMF_RELS "_rels/.rels"

/* An open 3MF file and the model parts read from it. */
struct tmf_doc {
	struct mio_src *s;
	zip_t *z;
	uint64_t cap;		 /* bytes all entries may unpack to */
	uint64_t budget;	 /* of which this many are left */
	struct tmf_part **parts; /* [0] is the root model part */
	size_t nparts, cap_parts;
	size_t meshes;		 /* mesh instances placed */
};

/* One entry being decompressed for the XML reader. */
struct tmf_stream {
	struct tmf_doc *d;
	zip_file_t *zf;
	const char *entry;
	int rc; /* 0, or the class of a failure already in the error */
};

/* libxml2 read callback: the next bytes of the entry, within the budget. */
static int stream_read(void *ctx, char *buf, int len)
{
	struct tmf_stream *st = ctx;
	zip_int64_t n;

	if (len <= 0)
		return 0;
	n = zip_fread(st->zf, buf, (zip_uint64_t)len);
	if (n < 0) {
		st->rc = mio_err(st->d->s, ST_ERR_PARSE, "zip entry %s cannot be decompressed: %s",
				 st->entry, zip_file_strerror(st->zf));
		return -1;
	}
	if ((uint64_t)n > st->d->budget) {
		st->rc = mio_err(st->d->s, ST_ERR_RANGE,
				 "zip entry %s unpacks to more than the %llu MiB Stratum reads from "
				 "a 3MF file (a zip bomb?)",
				 st->entry, (unsigned long long)(st->d->cap >> 20));
		return -1;
	}
	st->d->budget -= (uint64_t)n;
	return (int)n;
}

/*
 * Open entry name (case-insensitive, as OPC part names are) for streaming.
 * Returns 0, 1 if there is no such entry, or a negative class.
 */
static int open_entry(struct tmf_doc *d, const char *name, struct tmf_stream *st)
{
	zip_int64_t idx = zip_name_locate(d->z, name, ZIP_FL_NOCASE);
	zip_stat_t zs;

	memset(st, 0, sizeof(*st));
	st->d = d;
	st->entry = name;
	if (idx < 0)
		return 1;
	if (zip_stat_index(d->z, (zip_uint64_t)idx, 0, &zs) == 0 && (zs.valid & ZIP_STAT_SIZE) &&
	    zs.size > d->budget)
		return mio_err(d->s, ST_ERR_RANGE,
			       "zip entry %s says it unpacks to %llu bytes, more than the %llu MiB "
			       "Stratum reads from a 3MF file (a zip bomb?)",
			       name, (unsigned long long)zs.size, (unsigned long long)(d->cap >> 20));
	st->zf = zip_fopen_index(d->z, (zip_uint64_t)idx, 0);
	if (!st->zf)
		return mio_err(d->s, ST_ERR_PARSE, "zip entry %s cannot be opened: %s", name,
			       zip_strerror(d->z));
	return 0;
}

/* The loaded part for entry, parsing it on first use; NULL with the error set. */
static struct tmf_part *get_part(struct tmf_doc *d, const char *entry, int *rc)
{
	struct tmf_stream st;
	struct tmf_part *p;

	for (size_t i = 0; i < d->nparts; i++)
		if (!strcasecmp(d->parts[i]->entry, entry))
			return d->parts[i];
	struct tmf_part **q = st_grow(d->parts, &d->cap_parts, d->nparts + 1, sizeof(*q));

	if (!q)
		goto out_nomem;
	d->parts = q;
	*rc = open_entry(d, entry, &st);
	if (*rc == 1) {
		*rc = mio_err(d->s, ST_ERR_PARSE, "the 3MF names model part %s, which the zip does "
			      "not contain", entry);
		return NULL;
	}
	if (*rc)
		return NULL;
	p = calloc(1, sizeof(*p));
	if (!p || !(p->entry = strdup(entry))) {
		free(p);
		zip_fclose(st.zf);
		goto out_nomem;
	}
	*rc = tmf_parse_part(d->s, p, stream_read, &st, &st.rc);
	zip_fclose(st.zf);
	if (*rc) {
		tmf_part_free(p);
		free(p);
		return NULL;
	}
	d->parts[d->nparts++] = p;
	return p;
out_nomem:
	*rc = mio_err(d->s, ST_ERR_NOMEM, "out of memory reading %s", entry);
	return NULL;
}

/* The root model part's name: from _rels/.rels, else the usual one. */
static int root_entry(struct tmf_doc *d, char **entry)
{
	struct tmf_stream st;
	int rc = open_entry(d, TMF_RELS, &st);

	*entry = NULL;
	if (rc < 0)
		return rc;
	if (rc == 0) {
		rc = tmf_parse_rels(d->s, TMF_RELS, stream_read, &st, &st.rc, entry);
		zip_fclose(st.zf);
		if (rc)
			return rc;
	}
	if (*entry)
		return 0;
	if (zip_name_locate(d->z, TMF_DEFAULT_MODEL, ZIP_FL_NOCASE) < 0)
		return mio_err(d->s, ST_ERR_PARSE,
			       "a zip archive without a 3D model (no model relationship in "
			       TMF_RELS " and no " TMF_DEFAULT_MODEL "): not a 3MF file");
	*entry = strdup(TMF_DEFAULT_MODEL);
	return *entry ? 0 : mio_err(d->s, ST_ERR_NOMEM, "out of memory");
}

/* The object a reference from part names; NULL with the error set. */
static struct tmf_object *resolve(struct tmf_doc *d, struct tmf_part *from,
				  const struct tmf_ref *r, const char *what,
				  struct tmf_part **in, int *rc)
{
	struct tmf_part *p = r->path ? get_part(d, r->path, rc) : from;
	struct tmf_object *o;

	if (!p)
		return NULL;
	o = tmf_find_object(p, r->objectid);
	if (!o) {
		*rc = mio_err(d->s, ST_ERR_PARSE, "%s line %llu: %s refers to object %u, which %s "
			      "does not define",
			      from->entry, (unsigned long long)r->line, what, (unsigned)r->objectid,
			      p->entry);
		return NULL;
	}
	*in = p;
	return o;
}

/* Count the triangles o places (o->placed, saturated above TMF_PLACED_MAX). */
static int count_object(struct tmf_doc *d, struct tmf_part *p, struct tmf_object *o, int depth)
{
	uint64_t n = 0;
	int rc = 0;

	if (o->visit == 2)
		return 0;
	if (o->visit == 1)
		return mio_err(d->s, ST_ERR_PARSE, "%s line %llu: object %u contains itself "
			       "through its components",
			       p->entry, (unsigned long long)o->line, (unsigned)o->id);
	if (depth > TMF_NESTING_MAX)
		return mio_err(d->s, ST_ERR_RANGE, "%s line %llu: components nest more than %d "
			       "deep at object %u",
			       p->entry, (unsigned long long)o->line, TMF_NESTING_MAX,
			       (unsigned)o->id);
	o->visit = 1;
	if (o->type == TMF_NOT_SOLID)
		n = 0;
	else if (o->kind == TMF_MESH)
		n = o->ntris;
	for (size_t i = 0; o->type != TMF_NOT_SOLID && i < o->ncomps; i++) {
		struct tmf_part *cp;
		struct tmf_object *c = resolve(d, p, &o->comps[i], "a component", &cp, &rc);

		if (!c || (rc = count_object(d, cp, c, depth + 1)))
			return rc;
		n += c->placed;
		if (n > TMF_PLACED_MAX)
			n = TMF_PLACED_MAX + 1;
	}
	o->placed = n;
	o->visit = 2;
	return 0;
}

/* a then b: (p * a) * b, both in the 3MF row-vector convention. */
static struct tmf_transform compose(const struct tmf_transform *a, const struct tmf_transform *b)
{
	struct tmf_transform t;

	for (int i = 0; i < 4; i++)
		for (int j = 0; j < 3; j++) {
			double v = i == 3 ? b->m[9 + j] : 0.0;

			for (int k = 0; k < 3; k++)
				v += a->m[3 * i + k] * b->m[3 * k + j];
			t.m[3 * i + j] = v;
		}
	return t;
}

/* Determinant of the linear part: negative for a mirroring transform. */
static double det3(const struct tmf_transform *t)
{
	const double *m = t->m;

	return m[0] * (m[4] * m[8] - m[5] * m[7]) - m[1] * (m[3] * m[8] - m[5] * m[6]) +
	       m[2] * (m[3] * m[7] - m[4] * m[6]);
}

/* One placement of a mesh object: weld its used vertices, add its triangles. */
static int place_mesh(struct tmf_doc *d, struct tmf_part *p, const struct tmf_object *o,
		      const struct tmf_transform *t, double unit, struct mesh_builder *b)
{
	bool mirror = det3(t) < 0;
	struct st_error berr = {0};
	uint32_t *map;
	int rc = 0;

	if (!o->ntris)
		return 0;
	map = malloc(o->nverts * sizeof(*map));
	if (!map)
		return mio_err(d->s, ST_ERR_NOMEM, "out of memory placing object %u",
			       (unsigned)o->id);
	memset(map, 0xff, o->nverts * sizeof(*map));
	for (size_t i = 0; i < o->ntris && !rc; i++) {
		uint32_t c[3];

		for (int k = 0; k < 3; k++) {
			uint32_t v = o->tris[i][k];
			const double *x = o->verts[v];
			double q[3];

			if (map[v] != UINT32_MAX) {
				c[k] = map[v];
				continue;
			}
			for (int j = 0; j < 3; j++) {
				q[j] = (x[0] * t->m[j] + x[1] * t->m[3 + j] + x[2] * t->m[6 + j] +
					t->m[9 + j]) * unit;
				if (!isfinite(q[j])) {
					rc = mio_err(d->s, ST_ERR_PARSE,
						     "%s line %llu: vertex %lu of object %u is not "
						     "finite once transformed",
						     p->entry, (unsigned long long)o->line,
						     (unsigned long)v, (unsigned)o->id);
					goto out;
				}
			}
			if (mesh_builder_vertex(b, q, &map[v], &berr)) {
				rc = mio_err(d->s, berr.code, "%s", berr.msg);
				goto out;
			}
			c[k] = map[v];
		}
		/* A mirror turns the winding inside out; swap two corners back. */
		if (mesh_builder_triangle(b, c[0], mirror ? c[2] : c[1], mirror ? c[1] : c[2],
					  &berr))
			rc = mio_err(d->s, berr.code, "%s", berr.msg);
	}
	d->meshes++;
out:
	free(map);
	return rc;
}

/* Place o (counted already) through t: its mesh, or each component in turn. */
static int place_object(struct tmf_doc *d, struct tmf_part *p, const struct tmf_object *o,
			const struct tmf_transform *t, double unit, struct mesh_builder *b)
{
	int rc = 0;

	if (o->type == TMF_NOT_SOLID)
		return 0;
	if (o->kind == TMF_MESH)
		return place_mesh(d, p, o, t, unit, b);
	for (size_t i = 0; i < o->ncomps && !rc; i++) {
		struct tmf_part *cp;
		struct tmf_object *c = resolve(d, p, &o->comps[i], "a component", &cp, &rc);
		struct tmf_transform ct;

		if (!c)
			return rc;
		ct = compose(&o->comps[i].t, t);
		rc = place_object(d, cp, c, &ct, unit, b);
	}
	return rc;
}

/* Count, then place, every build item of the root part into *out. */
static int place_build(struct tmf_doc *d, struct mesh **out, struct meshio_info *info)
{
	struct tmf_part *root = d->parts[0];
	struct mesh_builder *b;
	uint64_t total = 0;
	size_t skipped = root->skipped_items;
	int rc = 0;

	if (!root->has_build)
		return mio_err(d->s, ST_ERR_PARSE, "%s has no <build>: nothing to print",
			       root->entry);
	for (size_t i = 0; i < root->nitems; i++) {
		const struct tmf_ref *r = &root->items[i];
		struct tmf_part *p;
		struct tmf_object *o = resolve(d, root, r, "build item", &p, &rc);

		if (!o)
			return rc;
		if (o->type == TMF_OTHER)
			return mio_err(d->s, ST_ERR_PARSE, "%s line %llu: build item places object "
				       "%u of type other, which 3MF does not allow",
				       root->entry, (unsigned long long)r->line, (unsigned)o->id);
		if ((rc = count_object(d, p, o, 0)))
			return rc;
		if (o->type == TMF_NOT_SOLID)
			skipped++;
		total += o->placed;
		if (total > TMF_PLACED_MAX)
			return mio_err(d->s, ST_ERR_RANGE, "%s: the build places more than %llu "
				       "triangles",
				       root->entry, TMF_PLACED_MAX);
	}
	if (!total)
		return mio_err(d->s, ST_ERR_PARSE, "%s: the build places no triangles (%zu items, "
			       "%zu of them not printable or not solid)",
			       root->entry, root->nitems + root->skipped_items, skipped);
	b = mesh_builder_new((size_t)total);
	if (!b)
		return mio_err(d->s, ST_ERR_NOMEM, "out of memory for %llu triangles",
			       (unsigned long long)total);
	for (size_t i = 0; i < root->nitems && !rc; i++) {
		struct tmf_part *p;
		struct tmf_object *o = resolve(d, root, &root->items[i], "build item", &p, &rc);

		if (o)
			rc = place_object(d, p, o, &root->items[i].t, root->unit, b);
	}
	if (rc) {
		mesh_builder_free(b);
		return rc;
	}
	*out = mesh_builder_finish(b);
	if (!*out)
		return mio_err(d->s, ST_ERR_NOMEM, "out of memory finishing the mesh");
	if (info) {
		info->items = root->nitems - (skipped - root->skipped_items);
		info->skipped_items = skipped;
		info->meshes = d->meshes;
		info->objects = 0;
		for (size_t i = 0; i < d->nparts; i++)
			info->objects += d->parts[i]->nobjs;
	}
	return 0;
}

/* Open the zip behind s: its file by name, or its buffer. */
static int open_zip(struct mio_src *s, zip_t **z)
{
	zip_error_t ze;
	zip_source_t *src;
	int rc;

	zip_error_init(&ze);
	if (s->f)
		src = zip_source_file_create(s->name, 0, -1, &ze);
	else
		src = zip_source_buffer_create(s->p, (zip_uint64_t)(s->end - s->p), 0, &ze);
	if (!src) {
		rc = mio_err(s, ST_ERR_NOMEM, "cannot open as a zip archive: %s",
			     zip_error_strerror(&ze));
		goto out;
	}
	*z = zip_open_from_source(src, ZIP_RDONLY, &ze);
	if (!*z) {
		zip_source_free(src);
		rc = mio_err(s, zip_error_code_zip(&ze) == ZIP_ER_MEMORY ? ST_ERR_NOMEM
									: ST_ERR_PARSE,
			     "not a readable zip archive (a 3MF file is one): %s",
			     zip_error_strerror(&ze));
		goto out;
	}
	rc = 0;
out:
	zip_error_fini(&ze);
	return rc;
}

/* Close the zip and free every part. */
static void doc_free(struct tmf_doc *d)
{
	for (size_t i = 0; i < d->nparts; i++) {
		tmf_part_free(d->parts[i]);
		free(d->parts[i]);
	}
	free(d->parts);
	if (d->z)
		zip_discard(d->z);
}

int threemf_read(struct mio_src *s, struct mesh **out, struct meshio_info *info)
{
	struct tmf_doc d;
	char *entry = NULL;
	int rc;

	*out = NULL;
	memset(&d, 0, sizeof(d));
	d.s = s;
	d.cap = d.budget = TMF_UNPACK_MAX;
	if ((rc = open_zip(s, &d.z)))
		return rc;
	if (!(rc = root_entry(&d, &entry)) && get_part(&d, entry, &rc))
		rc = place_build(&d, out, info);
	free(entry);
	doc_free(&d);
	return rc;
}

int threemf_text(struct mio_src *s, const char *entry, char **text)
{
	struct tmf_doc d;
	struct tmf_stream st;
	size_t len = 0;
	char *buf = NULL;
	int rc;

	*text = NULL;
	memset(&d, 0, sizeof(d));
	d.s = s;
	d.cap = d.budget = TMF_CONFIG_MAX;
	if ((rc = open_zip(s, &d.z)))
		return rc;
	rc = open_entry(&d, entry, &st);
	if (rc == 1) {
		rc = 0;
		goto out;
	}
	if (rc)
		goto out;
	buf = malloc(TMF_CONFIG_MAX + 1);
	if (!buf) {
		rc = mio_err(s, ST_ERR_NOMEM, "out of memory for %s", entry);
		goto out_close;
	}
	for (;;) {
		int n = stream_read(&st, buf + len, (int)(TMF_CONFIG_MAX + 1 - len));

		if (n < 0) {
			rc = st.rc;
			goto out_close;
		}
		if (n == 0)
			break;
		len += (size_t)n;
	}
	buf[len] = '\0';
	*text = buf;
	buf = NULL;
out_close:
	zip_fclose(st.zf);
out:
	free(buf);
	doc_free(&d);
	return rc;
}
