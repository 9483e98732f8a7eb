/*
 * cmd_check.c - `stratum check FILE [--json] [--threads N]`: read a mesh,
 * report its topology (seed 001) and whether it is printable (seed 000
 * Definition 3.11).  Exit 0 printable, 1 not printable, 65 unreadable input.
 */
#include <jansson.h>
#include <malloc.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>

#include "clio.h"
#include "commands.h"
#include "mesh.h"
#include "meshio.h"
#include "st_error.h"

/* The help text around the option lines. */
static const char check_head[] =
    "usage: stratum check FILE [--json] [--threads N]\n"
    "\n"
    "Reads an STL (binary or ASCII), OBJ or OFF file and reports its topology:\n"
    "edges, holes, singular edges, components, Euler characteristic and genus,\n"
    "degenerate and duplicate triangles, exact self-intersections, orientation,\n"
    "volume, parts and cavities - and whether it is printable as it stands\n"
    "(Attene's Definition 3.11 for each part; parts may touch along edges or at\n"
    "vertices, cavities are closed shells facing inwards).  FILE '-' reads\n"
    "stdin.  See docs/check.md.\n"
    "\n";

/* Figures that explain a reason, for the text and JSON messages. */
static void reason_detail(const struct mesh_report *r, enum mesh_reason why, char *buf,
			  size_t cap)
{
	switch (why) {
	case MESH_REASON_IRREGULAR:
		snprintf(buf, cap, "%zu %s", r->irregular, mesh_reason_text(why));
		break;
	case MESH_REASON_DEGENERATE:
		snprintf(buf, cap, "%zu %s", r->degenerate, mesh_reason_text(why));
		break;
	case MESH_REASON_OPEN:
		snprintf(buf, cap,
			 "%s (%zu boundary edges in %zu loops, %zu odd singular edges, %zu singular "
			 "edges whose triangles do not pair up)",
			 mesh_reason_text(why), r->boundary_edges, r->boundary_loops,
			 r->odd_edges - r->boundary_edges, r->open_singular_edges);
		break;
	case MESH_REASON_MISNESTED:
		snprintf(buf, cap, "%zu %s", r->misnested_shells, mesh_reason_text(why));
		break;
	case MESH_REASON_SELF_INTERSECTION:
		snprintf(buf, cap, "%llu pairs of %s",
			 (unsigned long long)r->self_intersections, mesh_reason_text(why));
		break;
	case MESH_REASON_SEVERAL_PARTS:
		snprintf(buf, cap, "%zu %s", r->parts, mesh_reason_text(why));
		break;
	case MESH_REASON_NOT_MANIFOLD_CONNECTED:
		snprintf(buf, cap, "%zu %s (%zu singular edges, %zu non-manifold vertices)",
			 r->manifold_components, mesh_reason_text(why), r->singular_edges,
			 r->nonmanifold_vertices);
		break;
	case MESH_REASON_DUPLICATE:
		snprintf(buf, cap, "%zu %s", r->duplicates, mesh_reason_text(why));
		break;
	case MESH_REASON_INCONSISTENT_ORIENTATION:
		snprintf(buf, cap, "%s (%zu edges)", mesh_reason_text(why), r->flipped_edges);
		break;
	default:
		snprintf(buf, cap, "%s", mesh_reason_text(why));
		break;
	}
}

static json_t *reasons_json(const struct mesh_report *r, int from, int to)
{
	json_t *list = json_array();
	char text[200];

	for (int i = from; i < to; i++) {
		if (!r->reasons[i])
			continue;
		reason_detail(r, (enum mesh_reason)i, text, sizeof(text));
		json_array_append_new(list, json_pack("{s:s, s:s}", "code",
						      mesh_reason_code((enum mesh_reason)i),
						      "text", text));
	}
	return list;
}

static int print_json(const char *path, enum meshio_format fmt, const struct mesh_report *r)
{
	json_t *o = json_object();
	json_t *bbox = json_pack("{s:[f,f,f], s:[f,f,f]}", "min", r->bbox_min[0],
				 r->bbox_min[1], r->bbox_min[2], "max", r->bbox_max[0],
				 r->bbox_max[1], r->bbox_max[2]);

	cmd_json_set(o, "s:file", path, "s:format", meshio_format_name(fmt),
		     "z:input_triangles", r->input_triangles, "z:vertices", r->vertices,
		     "z:edges", r->edges, "z:triangles", r->triangles,
		     "z:boundary_edges", r->boundary_edges, "z:singular_edges", r->singular_edges,
		     "z:nonmanifold_vertices", r->nonmanifold_vertices,
		     "z:components", r->components, "z:manifold_components", r->manifold_components,
		     "z:parts", r->parts, "z:cavities", r->cavities,
		     "z:misnested_shells", r->misnested_shells,
		     "z:unpaired_singular_edges", r->open_singular_edges,
		     "z:boundary_loops", r->boundary_loops, "I:euler", (json_int_t)r->euler,
		     "o:genus", r->genus_defined ? json_integer((json_int_t)r->genus) : json_null(),
		     "z:irregular", r->irregular, "z:degenerate", r->degenerate,
		     "z:duplicates", r->duplicates,
		     "I:self_intersections", (json_int_t)r->self_intersections,
		     "b:orientable", r->orientable, "b:consistently_oriented", r->consistently_oriented,
		     "z:flipped_edges", r->flipped_edges, "f:volume", r->volume, "o:bbox", bbox,
		     "b:printable", r->printable,
		     "o:reasons", reasons_json(r, 0, MESH_REASON_FIRST_WARNING),
		     "o:warnings", reasons_json(r, MESH_REASON_FIRST_WARNING, MESH_REASON_COUNT),
		     NULL);
	return cmd_json_out(o, JSON_INDENT(2) | JSON_PRESERVE_ORDER | JSON_REAL_PRECISION(10));
}

static const char *yes_no(bool b)
{
	return b ? "yes" : "no";
}

static void print_text(const char *path, enum meshio_format fmt, const struct mesh_report *r)
{
	char text[200];

	printf("%s: %s, %zu triangles\n", path, meshio_format_name(fmt), r->input_triangles);
	printf("  vertices %zu, edges %zu, triangles %zu (after removing %zu irregular, "
	       "%zu degenerate, %zu duplicate)\n",
	       r->vertices, r->edges, r->triangles, r->irregular, r->degenerate, r->duplicates);
	printf("  boundary edges %zu in %zu loops, singular edges %zu, non-manifold vertices %zu\n",
	       r->boundary_edges, r->boundary_loops, r->singular_edges, r->nonmanifold_vertices);
	printf("  components %zu (%zu manifold-connected), Euler characteristic %lld, genus ",
	       r->components, r->manifold_components, r->euler);
	if (r->genus_defined)
		printf("%lld\n", r->genus);
	else
		printf("undefined (not closed, manifold and orientable)\n");
	printf("  parts %zu, cavities %zu", r->parts, r->cavities);
	if (r->misnested_shells)
		printf(", misnested shells %zu", r->misnested_shells);
	printf("\n  self-intersecting triangle pairs %llu\n",
	       (unsigned long long)r->self_intersections);
	printf("  orientable %s, consistently oriented %s", yes_no(r->orientable),
	       yes_no(r->consistently_oriented));
	if (r->flipped_edges)
		printf(" (%zu flipped edges)", r->flipped_edges);
	printf("\n  volume %.6g mm^3, size %.6g x %.6g x %.6g mm, from (%.6g, %.6g, %.6g)\n",
	       r->volume, r->bbox_max[0] - r->bbox_min[0], r->bbox_max[1] - r->bbox_min[1],
	       r->bbox_max[2] - r->bbox_min[2], r->bbox_min[0], r->bbox_min[1], r->bbox_min[2]);
	printf("printable: %s\n", yes_no(r->printable));
	for (int i = 0; i < MESH_REASON_COUNT; i++) {
		if (!r->reasons[i])
			continue;
		reason_detail(r, (enum mesh_reason)i, text, sizeof(text));
		printf("  %s %s: %s\n", i < MESH_REASON_FIRST_WARNING ? "reason " : "warning",
		       mesh_reason_code((enum mesh_reason)i), text);
	}
}

static int check_run(int argc, char **argv, struct clio *io)
{
	const char *path = NULL, *shown;
	bool json = false;
	int threads = 0;
	struct st_error err = {0};
	struct mesh_report rep;
	struct mesh *m = NULL;
	enum meshio_format fmt;
	int rc;

	const struct cmd_opt opts[] = {
	    CMD_OPT_FLAG("--json", &json, "one JSON object on stdout instead of the text report"),
	    CMD_OPT_THREADS(&threads, "cores for the self-intersection test (default: all)"),
	};
	const struct cmd_spec spec = {
	    .cmd = "stratum check", .head = check_head, CMD_TABLE(opts), .col = 16,
	    .tail = "\nExit status: 0 printable, 1 not printable, 2 usage, 65 unreadable input.\n",
	    .pos = &path, .npos = 1, .extra = "one file at a time ('%s' and '%s')"};

	rc = cmd_parse(&spec, argc, argv);
	if (rc)
		return rc < 0 ? ST_EXIT_OK : rc;
	if (!path) {
		cmd_usage(&spec, stderr);
		return ST_EXIT_USAGE;
	}
	/* Arrays freed by one pass are the next pass's memory: from the heap,
	 * kept there, instead of pages mapped fresh (and cleared by the
	 * kernel) for every array of a large mesh. */
	mallopt(M_MMAP_THRESHOLD, 32 << 20);
	mallopt(M_TRIM_THRESHOLD, 256 << 20);
	shown = path; /* the report names "-", not the spool */
	if ((rc = clio_input(io, &path, "")))
		return rc;

	if ((rc = cmd_read_mesh("stratum check", path, &m, &fmt)))
		return rc;
	rc = mesh_analyze(m, threads, &rep, &err);
	mesh_free(m);
	if (rc)
		return cmd_fail("stratum check", ST_EXIT_SOFTWARE, "%s: %s", path, err.msg);
	rc = cmd_report_end("stratum check", "report",
			    json ? print_json(shown, fmt, &rep) != 0 : (print_text(shown, fmt, &rep), 0));
	if (rc)
		return rc;
	return rep.printable ? ST_EXIT_OK : ST_EXIT_FAILURE;
}

/* "stratum check -" reads the mesh from stdin (clio.h). */
int cmd_check(int argc, char **argv)
{
	return clio_run("stratum check", check_run, argc, argv);
}
