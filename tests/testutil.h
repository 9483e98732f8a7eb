/*
 * testutil.h - helpers shared by the Check suites: scratch files and running
 * the built binary (path in $STRATUM_BIN, set by the Makefile); counting
 * and measuring the slicer's toolpaths.
 */
#ifndef STRATUM_TESTS_TESTUTIL_H
#define STRATUM_TESTS_TESTUTIL_H

#include <stdbool.h>
#include <stddef.h>
#include <stdio.h>

#include "meshio.h"
#include "gcode_writer.h"
#include "toolpath.h"

/* tu_scratch_init / tu_scratch_cleanup - make and remove the scratch
 * directory under $TMPDIR; check_main.c calls them around the whole run. */
void tu_scratch_init(void);
void tu_scratch_cleanup(void);

/*
 * tu_path - a path name inside the scratch directory.  Returns a pointer to
 * a static rotating buffer; copy it if you need it long.
 */
const char *tu_path(const char *name);

/* tu_write - write len bytes to path; aborts the test on failure. */
void tu_write(const char *path, const void *data, size_t len);

/* tu_write_str - write a NUL-terminated string to path. */
void tu_write_str(const char *path, const char *text);

/*
 * tu_write_zip - write a zip archive (libzip, deflated) with n entries:
 * names[i] holding the NUL-terminated texts[i].  Aborts the test on failure.
 */
void tu_write_zip(const char *path, const char *const *names, const char *const *texts,
		  size_t n);

/*
 * tu_slurp - the whole file at path in a new buffer (free it), NUL-terminated
 * one past *len.  Aborts the test on failure.
 */
void *tu_slurp(const char *path, size_t *len);

/* tu_dir_entries - the number of entries in directory dir (. and .. not counted). */
int tu_dir_entries(const char *dir);

/*
 * tu_expect_read_fail - reading the mesh file at path (meshio_read) and its
 * bytes data[0..len) under the same name (meshio_read_buffer) must both fail
 * with code and a NULL mesh, in the same one-line message that starts with
 * "PATH:" and contains every needle (a NULL-terminated list).
 */
void tu_expect_read_fail(const char *path, const void *data, size_t len, int code,
			 const char *const *needles);

/* The _rels/.rels of a 3MF whose model part is /3D/3dmodel.model. */
extern const char tu_3mf_rels[];

/*
 * tu_write_3mf - a 3MF at path whose 3D/3dmodel.model is model_xml (with
 * the _rels/.rels above).  tu_write_3mf_mesh - the same for m as one object
 * placed once without a transform, coordinates printed exactly (%.17g).
 */
void tu_write_3mf(const char *path, const char *model_xml);
void tu_write_3mf_mesh(const char *path, const struct mesh *m);
/* tu_write_3mf_boxes - a 3MF at path with one w x d x h box object (fx_box)
 * per row of cubes {w, d, h, x, y}, each placed once by a build item
 * translated by x, y. */
void tu_write_3mf_boxes(const char *path, const double (*cubes)[5], int n);
/* tu_zip_add - add (or replace) the entry name with text in the zip at path. */
void tu_zip_add(const char *path, const char *name, const char *text);

/*
 * tu_read_between - read the text file path into buf (cap bytes) and return
 * the text between the first @begin and the next @end after it, cut there
 * (in buf).  Aborts the test when the file or either marker is missing.
 */
char *tu_read_between(const char *path, char *buf, size_t cap, const char *begin,
		      const char *end);

/*
 * tu_round_trip - m as a printer gets it: written as fmt (binary or ASCII
 * STL) to the scratch file name, read back into a new mesh (mesh_free).
 * Aborts the test if either fails.
 */
struct mesh *tu_round_trip(const struct mesh *m, const char *name, enum meshio_format fmt);

/*
 * tu_run - run "$STRATUM_BIN <args>" through the shell with stdout and
 * stderr captured into out (NUL-terminated, truncated to cap).  Returns the
 * exit status, or -1 if it did not exit normally (a crash fails the test).
 */
int tu_run(char *out, size_t cap, const char *args_fmt, ...)
	__attribute__((format(printf, 3, 4)));

/* tu_sh - tu_run for any shell command line (stderr captured too). */
int tu_sh(char *out, size_t cap, const char *cmd_fmt, ...) __attribute__((format(printf, 3, 4)));

/* tu_bin - the binary under test: $STRATUM_BIN, else build/stratum. */
const char *tu_bin(void);

/*
 * TU_SANITIZED - 1 in the AddressSanitizer build (make test-asan, which
 * make check runs for every suite), 0 in the plain build (make test).  A
 * long end-to-end case that the plain build runs at full size runs under
 * the sanitizers on a shorter input: the same code, in make check's time
 * budget; the full sizes are in make test and make bench.
 */
#ifdef __SANITIZE_ADDRESS__
#define TU_SANITIZED 1
#else
#define TU_SANITIZED 0
#endif

/*
 * tu_marlin_log_next - the next entry of the simulated Marlin's execution
 * log (sim/marlin_sim.h: "N text" per line run): *n is N, or -1 for a line
 * that ran without a number ("- text"); *text is the command, in line (cap
 * bytes), without its newline.  The driver's own unnumbered "M105" probes
 * are left out: it sends one after a silence (a loaded machine makes one)
 * and Marlin runs it like any line, while a job's lines are always
 * numbered.  Returns 1 for an entry, 0 at the end of the log.
 */
int tu_marlin_log_next(FILE *log, char *line, size_t cap, long *n, const char **text);

/* tu_file_exists - 1 if path exists. */
int tu_file_exists(const char *path);

/* tu_gcode_mem - stack st written with s to memory (sum filled when not
 * NULL); the text (free it).  Aborts the test on failure. */
char *tu_gcode_mem(const struct layer_stack *st, const struct gcodew_settings *s,
		   struct gcodew_summary *sum);

/* One extrusion move read back from G-code: a line, or an arc around
 * (cx, cy) (G2 clockwise, G3 counter-clockwise, centre as I J). */
struct tu_move {
	int layer;	/* ;LAYER_CHANGE count */
	char role[32];	/* its ;TYPE: */
	bool arc, ccw;
	double x0, y0, x1, y1, cx, cy; /* mm */
	double e;	/* mm of filament */
};

struct tu_moves {
	struct tu_move *m; /* free() it */
	size_t n;
	size_t g1, arcs; /* G1 lines, G2/G3 lines */
};

/* tu_read_moves - the extrusions (moves in XY that push filament) of the
 * G-code text, absolute E with G92 E0 resets (not M83). */
struct tu_moves tu_read_moves(const char *text);

/* tu_moves_e - filament of the moves of role in r (NULL: all). */
double tu_moves_e(const struct tu_moves *r, const char *role);

/* tu_count_role - number of paths of role on layer l. */
size_t tu_count_role(const struct layer_paths *l, enum path_role role);

/* tu_path_length - length of the open polyline through p's points, nm. */
double tu_path_length(const struct toolpath *p);

struct region_report;
struct slicer_summary;

/*
 * tu_slice_region - m sliced with the library defaults (0.2 mm layers,
 * 0.45 mm walls, bed centre 100,100) into tu_path(name) and measured by
 * the region verifier (region.h; every layer has a section); the job's
 * summary into sum and the widest bead read back (mm) into width_max
 * unless NULL.  Free the report with region_report_free.
 */
struct region_report *tu_slice_region(const struct mesh *m, const char *name,
				      struct slicer_summary *sum, double *width_max);

#endif
