/*
 * threemf_xml.c - parse one 3MF model part (3D/3dmodel.model and the parts
 * it refers to) with libxml2's streaming reader, so memory follows the mesh
 * and not the XML text.  What is read (docs/repair.md "3MF"): <model unit>
 * and requiredextensions, <resources><object id type> with a <mesh>
 * (<vertices><vertex x y z>, <triangles><triangle v1 v2 v3>) or
 * <components><component objectid transform p:path>, and <build><item
 * objectid transform p:path printable>.  Everything else (metadata,
 * materials, colours, thumbnails, other namespaces) is skipped.
 *
 * Vertices are rounded to float32 as read (what lib3mf and PrusaSlicer
 * store); transforms stay double.  Every message names the zip entry and the XML line.  A DTD is refused
 * (the 3MF core spec forbids one), so no entity is ever expanded.
 */
#include "threemf_impl.h"
#include "st_grow.h"

#include <float.h>
#include <libxml/xmlreader.h>
#include <math.h>
#include <stdarg.h>
#include <stdlib.h>
#include <string.h>

/* Elements we track the nesting of; everything else is TMF_EL_OTHER. */
enum tmf_el {
	TMF_EL_NONE,
	TMF_EL_OTHER,
	TMF_EL_MODEL,
	TMF_EL_RESOURCES,
	TMF_EL_OBJECT,
	TMF_EL_MESH,
	TMF_EL_VERTICES,
	TMF_EL_TRIANGLES,
	TMF_EL_COMPONENTS,
	TMF_EL_BUILD,
};

/* Deepest nesting whose element names are remembered; deeper is "other". */
#define TMF_DEPTH_MAX 64
/* Longest transform attribute accepted (12 numbers of ST_NUMBER_MAX). */
#define TMF_TRANSFORM_MAX 1024

/* Extensions a file may require that change nothing about the geometry. */
static const char *const ok_extensions[] = {
    TMF_NS_CORE,
    TMF_NS_PRODUCTION,
    "http://schemas.microsoft.com/3dmanufacturing/material/2015/02",
};

struct tmf_parser {
	struct mio_src *s;
	struct tmf_part *p;
	const char *entry;	/* zip entry, for messages */
	xmlTextReaderPtr r;
	enum tmf_el stack[TMF_DEPTH_MAX];
	bool in_object;		/* p->objs[p->nobjs - 1] is open */
	bool xml_failed;	/* libxml2 reported an error (below) */
	unsigned long xml_line;
	char xml_msg[160];
};

/* Record libxml2's first error; the read loop turns it into the message. */
static void on_xml_error(void *arg, xmlErrorPtr e)
{
	struct tmf_parser *ps = arg;
	size_t n;

	if (ps->xml_failed || !e)
		return;
	ps->xml_failed = true;
	ps->xml_line = e->line > 0 ? (unsigned long)e->line : 0;
	snprintf(ps->xml_msg, sizeof(ps->xml_msg), "%s", e->message ? e->message : "error");
	n = strlen(ps->xml_msg);
	while (n && (ps->xml_msg[n - 1] == '\n' || ps->xml_msg[n - 1] == ' '))
		ps->xml_msg[--n] = '\0';
}

/* Line of the node under the reader (1-based; 0 if unknown). */
static unsigned long node_line(struct tmf_parser *ps)
{
	xmlNodePtr n = xmlTextReaderCurrentNode(ps->r);
	long l = n ? xmlGetLineNo(n) : -1;

	return l > 0 ? (unsigned long)l : 0;
}

/* Fill the error as "ENTRY line N: text" and return code. */
static int perr(struct tmf_parser *ps, int code, const char *fmt, ...)
    __attribute__((format(printf, 3, 4)));

static int perr(struct tmf_parser *ps, int code, const char *fmt, ...)
{
	va_list ap;
	int rc;

	va_start(ap, fmt);
	rc = mio_verr_line(ps->s, code, ps->entry, node_line(ps), fmt, ap);
	va_end(ap);
	return rc;
}

/* Grow *arr (of *cap elements of size) to hold one more than n (st_grow). */
static int grow(void *arr, size_t *cap, size_t n, size_t size)
{
	void **a = arr;
	void *q = n < SIZE_MAX ? st_grow(*a, cap, n + 1, size) : NULL;

	if (!q)
		return ST_ERR_NOMEM;
	*a = q;
	return 0;
}

static int out_of_memory(struct tmf_parser *ps)
{
	return perr(ps, ST_ERR_NOMEM, "out of memory");
}

/* A quoted, shortened copy of an attribute value for messages. */
static const char *shown(const xmlChar *v, char *buf, size_t cap)
{
	return mio_tokstr((const char *)v, buf, cap);
}

/* An xs:double attribute: finite, the number grammar of docs/errors.md. */
static int number_attr(struct tmf_parser *ps, const char *what, const xmlChar *v, double *out)
{
	char b[40];
	enum mio_num r = mio_parse_double((const char *)v, strlen((const char *)v), out);

	if (r == MIO_NUM_OK)
		return 0;
	return perr(ps, ST_ERR_PARSE, "%s %s is %s", what, shown(v, b, sizeof(b)),
		    r == MIO_NUM_NONFINITE ? "not finite" : "not a number");
}

/* A non-negative integer attribute no larger than max. */
static int index_attr(struct tmf_parser *ps, const char *what, const xmlChar *v,
		      long long max, uint32_t *out)
{
	char b[40];
	long long x;

	if (!mio_parse_int((const char *)v, strlen((const char *)v), &x) || x < 0 || x > max)
		return perr(ps, ST_ERR_PARSE, "%s %s is not a whole number from 0 to %lld", what,
			    shown(v, b, sizeof(b)), max);
	*out = (uint32_t)x;
	return 0;
}

/* XML white space, the separator of transform numbers. */
static bool xml_space(char c)
{
	return c == ' ' || c == '\t' || c == '\r' || c == '\n';
}

/* transform="m00 m01 m02 m10 m11 m12 m20 m21 m22 m30 m31 m32". */
static int transform_attr(struct tmf_parser *ps, const xmlChar *v, struct tmf_transform *t)
{
	const char *c = (const char *)v;
	char b[40];
	int n = 0;

	if (strlen(c) > TMF_TRANSFORM_MAX)
		return perr(ps, ST_ERR_PARSE, "transform is longer than %d characters",
			    TMF_TRANSFORM_MAX);
	for (;;) {
		char tok[MIO_NUM_MAX + 2];
		size_t len = 0;
		enum mio_num r;

		while (xml_space(*c))
			c++;
		if (!*c)
			break;
		while (c[len] && !xml_space(c[len]))
			len++;
		if (n == 12)
			return perr(ps, ST_ERR_PARSE, "transform %s has more than 12 numbers",
				    shown(v, b, sizeof(b)));
		if (len > MIO_NUM_MAX)
			return perr(ps, ST_ERR_PARSE, "transform number %d is too long", n + 1);
		memcpy(tok, c, len);
		tok[len] = '\0';
		r = mio_parse_double(tok, len, &t->m[n]);
		if (r != MIO_NUM_OK)
			return perr(ps, ST_ERR_PARSE, "transform number %d %s is %s", n + 1,
				    shown((const xmlChar *)tok, b, sizeof(b)),
				    r == MIO_NUM_NONFINITE ? "not finite" : "not a number");
		n++;
		c += len;
	}
	if (n != 12)
		return perr(ps, ST_ERR_PARSE, "transform has %d numbers, a 3MF transform has 12",
			    n);
	return 0;
}

/* True if the attribute under the reader is name in namespace ns (NULL: none). */
static bool attr_is(struct tmf_parser *ps, const char *name, const char *ns)
{
	const xmlChar *ln = xmlTextReaderConstLocalName(ps->r);
	const xmlChar *uri = xmlTextReaderConstNamespaceUri(ps->r);

	if (!ln || strcmp((const char *)ln, name))
		return false;
	return ns ? uri && !strcmp((const char *)uri, ns) : !uri;
}

/* The element's attributes, one at a time: 1 with the reader on one, 0 after the last. */
static int next_attr(struct tmf_parser *ps, bool first)
{
	int rc = first ? xmlTextReaderMoveToFirstAttribute(ps->r)
		       : xmlTextReaderMoveToNextAttribute(ps->r);

	if (rc != 1)
		xmlTextReaderMoveToElement(ps->r);
	return rc == 1;
}

/* Value of the attribute under the reader (never NULL). */
static const xmlChar *attr_value(struct tmf_parser *ps)
{
	const xmlChar *v = xmlTextReaderConstValue(ps->r);

	return v ? v : (const xmlChar *)"";
}

static const struct {
	const char *name;
	double mm;
} units[] = {
    {"micron", 0.001}, {"millimeter", 1.0}, {"centimeter", 10.0},
    {"inch", 25.4},    {"foot", 304.8},	    {"meter", 1000.0},
};

/* Is the namespace bound to prefix one whose content we can ignore or read? */
static int check_extension(struct tmf_parser *ps, const char *prefix)
{
	xmlChar *ns = xmlTextReaderLookupNamespace(ps->r, (const xmlChar *)prefix);
	char b[40];
	int rc = 0;

	if (!ns)
		return perr(ps, ST_ERR_PARSE,
			    "requiredextensions names prefix %s, which is not declared",
			    mio_tokstr(prefix, b, sizeof(b)));
	for (size_t i = 0; i < sizeof(ok_extensions) / sizeof(ok_extensions[0]); i++)
		if (!strcmp((const char *)ns, ok_extensions[i]))
			goto out;
	rc = perr(ps, ST_ERR_UNSUPPORTED, "the file requires the 3MF extension %.100s, which "
		  "Stratum does not read", (const char *)ns);
out:
	xmlFree(ns);
	return rc;
}

/* <model unit requiredextensions>. */
static int on_model(struct tmf_parser *ps)
{
	char b[40];
	int rc = 0;

	ps->p->unit = 1.0;
	for (bool first = true; next_attr(ps, first); first = false) {
		const xmlChar *v = attr_value(ps);

		if (attr_is(ps, "unit", NULL)) {
			size_t i, n = sizeof(units) / sizeof(units[0]);

			for (i = 0; i < n && strcmp((const char *)v, units[i].name); i++)
				;
			if (i == n) {
				rc = perr(ps, ST_ERR_PARSE,
					  "unit %s is not micron, millimeter, centimeter, inch, "
					  "foot or meter",
					  shown(v, b, sizeof(b)));
				break;
			}
			ps->p->unit = units[i].mm;
		} else if (attr_is(ps, "requiredextensions", NULL)) {
			const char *c = (const char *)v;

			while (*c && !rc) {
				char prefix[64];
				size_t len = 0;

				while (xml_space(*c))
					c++;
				while (c[len] && !xml_space(c[len]))
					len++;
				if (!len)
					break;
				if (len >= sizeof(prefix)) {
					rc = perr(ps, ST_ERR_PARSE,
						  "requiredextensions names a prefix longer than "
						  "%zu characters",
						  sizeof(prefix) - 1);
					break;
				}
				memcpy(prefix, c, len);
				prefix[len] = '\0';
				rc = check_extension(ps, prefix);
				c += len;
			}
			if (rc)
				break;
		}
	}
	xmlTextReaderMoveToElement(ps->r);
	return rc;
}

/* Largest ST_ResourceID (xs:positiveInteger below 2^31). */
#define TMF_ID_MAX 2147483647LL

/* <object id type>: open a new object. */
static int on_object(struct tmf_parser *ps)
{
	struct tmf_part *p = ps->p;
	struct tmf_object *o;
	bool have_id = false;
	char b[40];
	int rc;

	if (grow(&p->objs, &p->cap_objs, p->nobjs, sizeof(*p->objs)))
		return out_of_memory(ps);
	o = &p->objs[p->nobjs];
	memset(o, 0, sizeof(*o));
	o->line = node_line(ps);
	for (bool first = true; next_attr(ps, first); first = false) {
		const xmlChar *v = attr_value(ps);
		const char *t = (const char *)v;

		if (attr_is(ps, "id", NULL)) {
			if ((rc = index_attr(ps, "object id", v, TMF_ID_MAX, &o->id)))
				return rc;
			have_id = true;
		} else if (attr_is(ps, "type", NULL)) {
			if (!strcmp(t, "model") || !strcmp(t, "solidsupport"))
				o->type = TMF_SOLID;
			else if (!strcmp(t, "support") || !strcmp(t, "surface"))
				o->type = TMF_NOT_SOLID;
			else if (!strcmp(t, "other"))
				o->type = TMF_OTHER;
			else
				return perr(ps, ST_ERR_PARSE,
					    "object type %s is not one of model, solidsupport, "
					    "support, surface, other",
					    shown(v, b, sizeof(b)));
		}
	}
	if (!have_id)
		return perr(ps, ST_ERR_PARSE, "object has no id");
	p->nobjs++;
	ps->in_object = true;
	return 0;
}

/* The object being read (on_object opened it). */
static struct tmf_object *cur(struct tmf_parser *ps)
{
	return &ps->p->objs[ps->p->nobjs - 1];
}

/* <mesh> or <components>: an object is one or the other. */
static int set_kind(struct tmf_parser *ps, enum tmf_kind k)
{
	struct tmf_object *o = cur(ps);

	if (o->kind != TMF_EMPTY)
		return perr(ps, ST_ERR_PARSE, "object %u has more than one <mesh> or <components>",
			    (unsigned)o->id);
	o->kind = k;
	return 0;
}

/* <vertex x y z>. */
static int on_vertex(struct tmf_parser *ps)
{
	struct tmf_object *o = cur(ps);
	double v[3];
	int seen = 0, rc;

	for (bool first = true; next_attr(ps, first); first = false) {
		for (int k = 0; k < 3; k++) {
			static const char *const axis[] = {"x", "y", "z"};

			if (attr_is(ps, axis[k], NULL)) {
				if ((rc = number_attr(ps, axis[k], attr_value(ps), &v[k])))
					return rc;
				seen |= 1 << k;
			}
		}
	}
	if (seen != 7)
		return perr(ps, ST_ERR_PARSE, "vertex %zu of object %u lacks x, y or z", o->nverts,
			    (unsigned)o->id);
	/* Held as float32, as lib3mf and PrusaSlicer hold them: a PrusaSlicer
	 * 3MF then gives its STL's coordinates bit for bit (docs/repair.md). */
	for (int k = 0; k < 3; k++) {
		if (fabs(v[k]) > FLT_MAX)
			return perr(ps, ST_ERR_PARSE, "vertex %zu of object %u: %g is beyond the "
				    "float32 range of 3MF coordinates",
				    o->nverts, (unsigned)o->id, v[k]);
		v[k] = (double)(float)v[k];
	}
	if (o->nverts >= MESH_MAX_ELEMENTS)
		return perr(ps, ST_ERR_RANGE, "object %u has more than %lu vertices",
			    (unsigned)o->id, (unsigned long)MESH_MAX_ELEMENTS);
	if (grow(&o->verts, &o->cap_verts, o->nverts, sizeof(*o->verts)))
		return out_of_memory(ps);
	memcpy(o->verts[o->nverts++], v, sizeof(v));
	return 0;
}

/* <triangle v1 v2 v3>: indices into the vertices read so far. */
static int on_triangle(struct tmf_parser *ps)
{
	struct tmf_object *o = cur(ps);
	uint32_t t[3];
	int seen = 0, rc;

	for (bool first = true; next_attr(ps, first); first = false) {
		for (int k = 0; k < 3; k++) {
			static const char *const corner[] = {"v1", "v2", "v3"};

			if (attr_is(ps, corner[k], NULL)) {
				if ((rc = index_attr(ps, corner[k], attr_value(ps),
						     (long long)MESH_MAX_ELEMENTS, &t[k])))
					return rc;
				seen |= 1 << k;
			}
		}
	}
	if (seen != 7)
		return perr(ps, ST_ERR_PARSE, "triangle %zu of object %u lacks v1, v2 or v3",
			    o->ntris, (unsigned)o->id);
	for (int k = 0; k < 3; k++)
		if (t[k] >= o->nverts)
			return perr(ps, ST_ERR_PARSE,
				    "triangle %zu of object %u refers to vertex %lu, but the "
				    "object has %zu vertices before it",
				    o->ntris, (unsigned)o->id, (unsigned long)t[k], o->nverts);
	if (o->ntris >= MESH_MAX_ELEMENTS)
		return perr(ps, ST_ERR_RANGE, "object %u has more than %lu triangles",
			    (unsigned)o->id, (unsigned long)MESH_MAX_ELEMENTS);
	if (grow(&o->tris, &o->cap_tris, o->ntris, sizeof(*o->tris)))
		return out_of_memory(ps);
	memcpy(o->tris[o->ntris++], t, sizeof(t));
	return 0;
}

/* The identity transform, for a reference without one. */
static void identity(struct tmf_transform *t)
{
	memset(t, 0, sizeof(*t));
	t->m[0] = t->m[4] = t->m[8] = 1.0;
}

/*
 * <component objectid transform p:path> or <item ...>: fill r.  *printable
 * (items only, may be NULL) is cleared by printable="0".
 */
static int on_ref(struct tmf_parser *ps, const char *what, struct tmf_ref *r, bool *printable)
{
	bool have_id = false;
	int rc;

	memset(r, 0, sizeof(*r));
	identity(&r->t);
	r->line = node_line(ps);
	for (bool first = true; next_attr(ps, first); first = false) {
		const xmlChar *v = attr_value(ps);

		if (attr_is(ps, "objectid", NULL)) {
			if ((rc = index_attr(ps, "objectid", v, TMF_ID_MAX, &r->objectid)))
				return rc;
			have_id = true;
		} else if (attr_is(ps, "transform", NULL)) {
			if ((rc = transform_attr(ps, v, &r->t)))
				return rc;
		} else if (attr_is(ps, "path", TMF_NS_PRODUCTION)) {
			const char *path = (const char *)v;

			free(r->path);
			r->path = strdup(path[0] == '/' ? path + 1 : path);
			if (!r->path)
				return out_of_memory(ps);
		} else if (printable && attr_is(ps, "printable", NULL)) {
			*printable = strcmp((const char *)v, "0") && strcmp((const char *)v, "false");
		}
	}
	if (!have_id)
		return perr(ps, ST_ERR_PARSE, "%s has no objectid", what);
	return 0;
}

static int on_component(struct tmf_parser *ps)
{
	struct tmf_object *o = cur(ps);
	int rc;

	if (grow(&o->comps, &o->cap_comps, o->ncomps, sizeof(*o->comps)))
		return out_of_memory(ps);
	rc = on_ref(ps, "component", &o->comps[o->ncomps], NULL);
	/* Counted even on failure so tmf_part_free frees a path it got. */
	o->ncomps++;
	return rc;
}

static int on_item(struct tmf_parser *ps)
{
	struct tmf_part *p = ps->p;
	bool printable = true;
	int rc;

	if (grow(&p->items, &p->cap_items, p->nitems, sizeof(*p->items)))
		return out_of_memory(ps);
	rc = on_ref(ps, "build item", &p->items[p->nitems], &printable);
	p->nitems++;
	if (rc == 0 && !printable) {
		free(p->items[--p->nitems].path);
		p->skipped_items++;
	}
	return rc;
}

/* End of an <object>: it must have said what it is. */
static int end_object(struct tmf_parser *ps)
{
	struct tmf_object *o = cur(ps);

	ps->in_object = false;
	if (o->kind == TMF_EMPTY)
		return perr(ps, ST_ERR_PARSE, "object %u has neither <mesh> nor <components>",
			    (unsigned)o->id);
	return 0;
}

/* Local name of the element under the reader if it is in the core namespace. */
static const char *core_name(struct tmf_parser *ps)
{
	const xmlChar *uri = xmlTextReaderConstNamespaceUri(ps->r);
	const xmlChar *ln = xmlTextReaderConstLocalName(ps->r);

	if (!uri || strcmp((const char *)uri, TMF_NS_CORE) || !ln)
		return NULL;
	return (const char *)ln;
}

/* Classify and handle an element start with parent; *el gets its kind. */
static int on_start(struct tmf_parser *ps, enum tmf_el parent, int depth, enum tmf_el *el)
{
	const char *n = core_name(ps);

	*el = TMF_EL_OTHER;
	if (depth == 0) {
		if (!n || strcmp(n, "model"))
			return perr(ps, ST_ERR_PARSE, "the root element is not a 3MF <model> of "
				    "namespace " TMF_NS_CORE);
		*el = TMF_EL_MODEL;
		return on_model(ps);
	}
	if (!n)
		return 0;
	if (parent == TMF_EL_MODEL && !strcmp(n, "resources"))
		*el = TMF_EL_RESOURCES;
	else if (parent == TMF_EL_MODEL && !strcmp(n, "build")) {
		if (ps->p->has_build)
			return perr(ps, ST_ERR_PARSE, "more than one <build>");
		ps->p->has_build = true;
		*el = TMF_EL_BUILD;
	} else if (parent == TMF_EL_RESOURCES && !strcmp(n, "object")) {
		*el = TMF_EL_OBJECT;
		return on_object(ps);
	} else if (parent == TMF_EL_OBJECT && !strcmp(n, "mesh")) {
		*el = TMF_EL_MESH;
		return set_kind(ps, TMF_MESH);
	} else if (parent == TMF_EL_OBJECT && !strcmp(n, "components")) {
		*el = TMF_EL_COMPONENTS;
		return set_kind(ps, TMF_COMPONENTS);
	} else if (parent == TMF_EL_MESH && !strcmp(n, "vertices"))
		*el = TMF_EL_VERTICES;
	else if (parent == TMF_EL_MESH && !strcmp(n, "triangles"))
		*el = TMF_EL_TRIANGLES;
	else if (parent == TMF_EL_VERTICES && !strcmp(n, "vertex"))
		return on_vertex(ps);
	else if (parent == TMF_EL_TRIANGLES && !strcmp(n, "triangle"))
		return on_triangle(ps);
	else if (parent == TMF_EL_COMPONENTS && !strcmp(n, "component"))
		return on_component(ps);
	else if (parent == TMF_EL_BUILD && !strcmp(n, "item"))
		return on_item(ps);
	return 0;
}

/* Sort key of objects. */
static int by_id(const void *a, const void *b)
{
	const struct tmf_object *x = a, *y = b;

	return x->id < y->id ? -1 : x->id > y->id;
}

/* After the whole part: sort the objects and refuse a repeated id. */
static int finish(struct tmf_parser *ps)
{
	struct tmf_part *p = ps->p;

	if (p->nobjs > 1) /* qsort may not take NULL, even with no element */
		qsort(p->objs, p->nobjs, sizeof(*p->objs), by_id);
	for (size_t i = 1; i < p->nobjs; i++)
		if (p->objs[i].id == p->objs[i - 1].id) {
			const struct tmf_object *a = &p->objs[i - 1], *b = &p->objs[i];
			uint64_t l1 = a->line < b->line ? a->line : b->line;
			uint64_t l2 = a->line < b->line ? b->line : a->line;

			return mio_err(ps->s, ST_ERR_PARSE,
				       "%s line %llu: object id %u is defined again (first on line "
				       "%llu)",
				       p->entry, (unsigned long long)l2, (unsigned)a->id,
				       (unsigned long long)l1);
		}
	return 0;
}

/* The message for a failed read: the read callback's (size cap, bad zip data), or libxml2's. */
static int xml_error(struct tmf_parser *ps, const int *read_rc)
{
	if (*read_rc)
		return *read_rc; /* the callback filled the message */
	if (ps->xml_failed)
		return mio_err(ps->s, ST_ERR_PARSE, "%s line %lu: not well-formed XML: %s",
			       ps->entry, ps->xml_line, ps->xml_msg);
	return mio_err(ps->s, ST_ERR_PARSE, "%s: cannot be read as XML", ps->entry);
}

/* Start a streaming reader over read(ctx); no network, no DTD loading. */
static int open_reader(struct tmf_parser *ps, struct mio_src *s, const char *entry,
		       tmf_read_fn read, void *ctx)
{
	memset(ps, 0, sizeof(*ps));
	ps->s = s;
	ps->entry = entry;
	xmlInitParser();
	ps->r = xmlReaderForIO(read, NULL, ctx, NULL, NULL, XML_PARSE_NONET | XML_PARSE_BIG_LINES);
	if (!ps->r)
		return mio_err(s, ST_ERR_NOMEM, "%s: out of memory for the XML reader", entry);
	xmlTextReaderSetStructuredErrorHandler(ps->r, on_xml_error, ps);
	return 0;
}

/*
 * Advance to the next node: 1 on one, 0 at the end, <0 with the error
 * filled (bad XML, a DTD, or the read callback's own failure).
 */
static int next_node(struct tmf_parser *ps, const int *read_rc)
{
	int r = xmlTextReaderRead(ps->r);

	if (r < 0 || ps->xml_failed)
		return xml_error(ps, read_rc);
	if (r == 1 && xmlTextReaderNodeType(ps->r) == XML_READER_TYPE_DOCUMENT_TYPE)
		return perr(ps, ST_ERR_PARSE, "has a <!DOCTYPE>, which 3MF does not allow");
	return r;
}

int tmf_parse_part(struct mio_src *s, struct tmf_part *p, tmf_read_fn read, void *ctx,
		   const int *read_rc)
{
	struct tmf_parser ps;
	bool root = false;
	int rc, r;

	p->unit = 1.0;
	if ((rc = open_reader(&ps, s, p->entry, read, ctx)))
		return rc;
	ps.p = p;
	while ((r = next_node(&ps, read_rc)) == 1) {
		int type = xmlTextReaderNodeType(ps.r), depth = xmlTextReaderDepth(ps.r);
		enum tmf_el parent, el;

		if (depth < 0)
			continue;
		if (type == XML_READER_TYPE_END_ELEMENT) {
			if (depth < TMF_DEPTH_MAX && ps.stack[depth] == TMF_EL_OBJECT &&
			    (rc = end_object(&ps)))
				break;
			continue;
		}
		if (type != XML_READER_TYPE_ELEMENT)
			continue;
		root = true;
		parent = depth == 0 ? TMF_EL_NONE
				    : depth <= TMF_DEPTH_MAX ? ps.stack[depth - 1] : TMF_EL_OTHER;
		if ((rc = on_start(&ps, parent, depth, &el)))
			break;
		if (xmlTextReaderIsEmptyElement(ps.r)) {
			if (el == TMF_EL_OBJECT && (rc = end_object(&ps)))
				break;
		} else if (depth < TMF_DEPTH_MAX) {
			ps.stack[depth] = el;
		}
	}
	if (!rc && r < 0)
		rc = r;
	else if (!rc && !root)
		rc = mio_err(s, ST_ERR_PARSE, "%s: no XML content", p->entry);
	if (!rc)
		rc = finish(&ps);
	xmlFreeTextReader(ps.r);
	return rc;
}

/* The OPC relationships namespace and the 3MF type of the model part. */
#define TMF_NS_RELS "http://schemas.openxmlformats.org/package/2006/relationships"
#define TMF_REL_MODEL "http://schemas.microsoft.com/3dmanufacturing/2013/01/3dmodel"

int tmf_parse_rels(struct mio_src *s, const char *entry, tmf_read_fn read, void *ctx,
		   const int *read_rc, char **target)
{
	struct tmf_parser ps;
	int rc, r = 0;

	*target = NULL;
	if ((rc = open_reader(&ps, s, entry, read, ctx)))
		return rc;
	while (!*target && !rc && (r = next_node(&ps, read_rc)) == 1) {
		const xmlChar *uri = xmlTextReaderConstNamespaceUri(ps.r);
		const xmlChar *ln = xmlTextReaderConstLocalName(ps.r);
		xmlChar *type, *t;

		if (xmlTextReaderNodeType(ps.r) != XML_READER_TYPE_ELEMENT || !uri || !ln ||
		    strcmp((const char *)uri, TMF_NS_RELS) || strcmp((const char *)ln, "Relationship"))
			continue;
		type = xmlTextReaderGetAttribute(ps.r, (const xmlChar *)"Type");
		t = xmlTextReaderGetAttribute(ps.r, (const xmlChar *)"Target");
		if (type && t && !strcmp((const char *)type, TMF_REL_MODEL)) {
			const char *path = (const char *)t;

			*target = strdup(path[0] == '/' ? path + 1 : path);
			if (!*target)
				rc = perr(&ps, ST_ERR_NOMEM, "out of memory");
		}
		xmlFree(type);
		xmlFree(t);
	}
	if (!rc && r < 0)
		rc = r;
	xmlFreeTextReader(ps.r);
	if (rc) {
		free(*target);
		*target = NULL;
	}
	return rc;
}

void tmf_part_free(struct tmf_part *p)
{
	if (!p)
		return;
	for (size_t i = 0; i < p->nobjs; i++) {
		struct tmf_object *o = &p->objs[i];

		free(o->verts);
		free(o->tris);
		for (size_t k = 0; k < o->ncomps; k++)
			free(o->comps[k].path);
		free(o->comps);
	}
	/* An object that failed mid-way was not counted: nothing of it is left. */
	free(p->objs);
	for (size_t i = 0; i < p->nitems; i++)
		free(p->items[i].path);
	free(p->items);
	free(p->entry);
	memset(p, 0, sizeof(*p));
}

struct tmf_object *tmf_find_object(struct tmf_part *p, uint32_t id)
{
	struct tmf_object key;

	key.id = id;
	return bsearch(&key, p->objs, p->nobjs, sizeof(*p->objs), by_id);
}
