/*
 * threemf_impl.h - private to repair/threemf*.c: one 3MF model part (an XML
 * file inside the zip) as parsed, before its build is placed.
 *
 * threemf_xml.c parses a model part into a struct tmf_part (objects with
 * their raw vertices, triangles or components, and the build items);
 * threemf.c opens the zip, streams parts to the parser under a size cap,
 * resolves references between parts and places every build item.
 */
#ifndef STRATUM_REPAIR_THREEMF_IMPL_H
#define STRATUM_REPAIR_THREEMF_IMPL_H

#include <stdbool.h>
#include <stddef.h>
#include <stdint.h>

#include "meshio_impl.h"

/* The core namespace; elements of other namespaces are skipped. */
#define TMF_NS_CORE "http://schemas.microsoft.com/3dmanufacturing/core/2015/02"
/* The production extension: its p:path lets items and components point into
 * other model parts (Bambu Studio writes one part per object). */
#define TMF_NS_PRODUCTION "http://schemas.microsoft.com/3dmanufacturing/production/2015/06"

/* A 3x4 affine transform, row-vector convention of the 3MF core spec:
 * p' = (x y z 1) * M, so x' = x*m[0] + y*m[3] + z*m[6] + m[9]. */
struct tmf_transform {
	double m[12];
};

/* A reference to an object: a component of an object, or a build item. */
struct tmf_ref {
	uint32_t objectid;
	char *path;		   /* p:path (no leading '/'), NULL: this part */
	struct tmf_transform t;
	uint64_t line;		   /* where it is written, for messages */
};

enum tmf_kind {
	TMF_EMPTY, /* neither <mesh> nor <components> seen (yet) */
	TMF_MESH,
	TMF_COMPONENTS,
};

/* The object's type attribute, as far as placing it matters. */
enum tmf_type {
	TMF_SOLID,     /* model (the default) or solidsupport */
	TMF_NOT_SOLID, /* support or surface: not printed as a solid, skipped */
	TMF_OTHER,     /* other: a build item must not place it */
};

struct tmf_object {
	uint32_t id;
	enum tmf_kind kind;
	enum tmf_type type;
	uint64_t line;		/* of the <object> tag */
	double (*verts)[3];	/* as written, in the model's unit */
	size_t nverts, cap_verts;
	uint32_t (*tris)[3];	/* indices into verts, checked */
	size_t ntris, cap_tris;
	struct tmf_ref *comps;
	size_t ncomps, cap_comps;
	/* Placement state (threemf.c): 0 not seen, 1 being counted (a cycle
	 * if met again), 2 counted; placed is its triangle count, saturated. */
	int visit;
	uint64_t placed;
};

struct tmf_part {
	char *entry;		/* zip entry name, for messages */
	double unit;		/* mm per model unit */
	struct tmf_object *objs; /* sorted by id once parsed */
	size_t nobjs, cap_objs;
	struct tmf_ref *items;	/* the build, in order */
	size_t nitems, cap_items;
	bool has_build;
	size_t skipped_items;	/* printable="0" */
};

/* Reads bytes of the part into buf; returns the count, 0 at the end, -1 on error. */
typedef int (*tmf_read_fn)(void *ctx, char *buf, int len);

/*
 * tmf_parse_part - parse one model part from read(ctx) into p (entry set
 * by the caller, the rest zeroed).  Messages go through s (file name) and
 * name the entry and the XML line.  When read fails it fills the error
 * itself and sets *read_rc, which is then returned.  Returns 0 or a
 * negative class.
 */
int tmf_parse_part(struct mio_src *s, struct tmf_part *p, tmf_read_fn read, void *ctx,
		   const int *read_rc);

/*
 * tmf_parse_rels - find the 3D model part in a relationships part
 * (_rels/.rels): *target gets the Target of the first relationship of the
 * 3D model type, without its leading '/' (malloc'd), or NULL if there is
 * none.  Errors as tmf_parse_part; entry names the part in messages.
 */
int tmf_parse_rels(struct mio_src *s, const char *entry, tmf_read_fn read, void *ctx,
		   const int *read_rc, char **target);

/* tmf_part_free - free what tmf_parse_part allocated (p itself is the caller's). */
void tmf_part_free(struct tmf_part *p);

/* The object with id in p (objs sorted), or NULL. */
struct tmf_object *tmf_find_object(struct tmf_part *p, uint32_t id);

#endif /* STRATUM_REPAIR_THREEMF_IMPL_H */
