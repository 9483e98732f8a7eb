/*
 * clip.cpp - the Clipper bridge behind clip.h: converts the C containers to
 * ClipperLib::Paths and back, and turns every exception into an error code
 * (STYLE rule 14).  The containers are malloc'd here and freed here.
 */
#include "clip.h"
#include "st_grow.h"

#include <cmath>
#include <cstdlib>
#include <cstring>
#include <exception>
#include <limits>
#include <map>
#include <memory>
#include <new>
#include <type_traits>
#include <vector>

#include <polyclipping/clipper.hpp>

namespace {

using ClipperLib::IntPoint;
using ClipperLib::Path;
using ClipperLib::Paths;

// Grow a malloc'd array to hold at least need elements (st_grow.h's rule);
// throws bad_alloc.
template <class T> void reserve(T *&arr, size_t &cap, size_t need)
{
	if (need <= cap)
		return;
	T *grown = static_cast<T *>(st_grow(arr, &cap, need, sizeof(T)));
	if (!grown)
		throw std::bad_alloc();
	arr = grown;
}

// Append one path to ps; throws bad_alloc (ps unchanged then).
void push_path(struct clip_paths *ps, const int64_t *xy, size_t npts)
{
	size_t have = clip_paths_points(ps);

	if (npts > std::numeric_limits<size_t>::max() / 2 - have)
		throw std::bad_alloc();
	reserve(ps->start, ps->cap_paths, ps->n + 2);
	reserve(ps->xy, ps->cap_pts, 2 * (have + npts));
	if (npts)
		std::memcpy(ps->xy + 2 * have, xy, 2 * npts * sizeof(*xy));
	ps->start[ps->n] = have;
	ps->start[ps->n + 1] = have + npts;
	ps->n++;
}

void push_path(struct clip_paths *ps, const Path &p)
{
	size_t have = clip_paths_points(ps);

	reserve(ps->start, ps->cap_paths, ps->n + 2);
	reserve(ps->xy, ps->cap_pts, 2 * (have + p.size()));
	for (size_t j = 0; j < p.size(); j++) {
		ps->xy[2 * (have + j)] = p[j].X;
		ps->xy[2 * (have + j) + 1] = p[j].Y;
	}
	ps->start[ps->n] = have;
	ps->start[ps->n + 1] = have + p.size();
	ps->n++;
}

Path to_path(const int64_t *xy, size_t npts)
{
	Path p;
	p.reserve(npts);
	for (size_t j = 0; j < npts; j++)
		p.push_back(IntPoint(xy[2 * j], xy[2 * j + 1]));
	return p;
}

Paths to_paths(const struct clip_paths *ps)
{
	Paths out;
	if (!ps)
		return out;
	out.reserve(ps->n);
	for (size_t i = 0; i < ps->n; i++)
		out.push_back(to_path(clip_path_xy(ps, i), clip_path_len(ps, i)));
	return out;
}

void from_paths(const Paths &in, struct clip_paths *out)
{
	clip_paths_clear(out);
	for (const Path &p : in)
		if (!p.empty())
			push_path(out, p);
}

// Start a new expolygon at the next path index.
void open_expoly(struct clip_expolys *ex)
{
	reserve(ex->first, ex->cap, ex->n + 2);
	ex->first[ex->n] = ex->paths.n;
	ex->n++;
}

// Outer node o with its holes becomes one expolygon; islands inside the
// holes follow as expolygons of their own.
void add_outer(const ClipperLib::PolyNode &o, struct clip_expolys *ex)
{
	open_expoly(ex);
	push_path(&ex->paths, o.Contour);
	for (const ClipperLib::PolyNode *h : o.Childs)
		push_path(&ex->paths, h->Contour);
	ex->first[ex->n] = ex->paths.n;
	for (const ClipperLib::PolyNode *h : o.Childs)
		for (const ClipperLib::PolyNode *island : h->Childs)
			add_outer(*island, ex);
}

void from_tree(const ClipperLib::PolyTree &tree, struct clip_expolys *out)
{
	clip_expolys_clear(out);
	for (const ClipperLib::PolyNode *o : tree.Childs)
		if (!o->IsOpen())
			add_outer(*o, out);
}

const ClipperLib::ClipType clip_types[CLIP_OPS] = {ClipperLib::ctUnion, ClipperLib::ctDifference,
						   ClipperLib::ctIntersection, ClipperLib::ctXor};
const ClipperLib::PolyFillType fill_types[CLIP_FILLS] = {
	ClipperLib::pftEvenOdd, ClipperLib::pftNonZero, ClipperLib::pftPositive,
	ClipperLib::pftNegative};
const ClipperLib::JoinType join_types[CLIP_JOINS] = {ClipperLib::jtMiter, ClipperLib::jtRound,
						     ClipperLib::jtSquare};
const ClipperLib::EndType end_types[CLIP_ENDS] = {ClipperLib::etOpenButt,
						  ClipperLib::etOpenSquare, ClipperLib::etOpenRound};

// The value a C caller stored in an enum parameter, read as bytes: in C++
// loading an out-of-range value through the enum type is undefined, and
// the range check must come first.
template <class E> unsigned raw(const E &e)
{
	std::underlying_type_t<E> v;
	std::memcpy(&v, &e, sizeof(v));
	return static_cast<unsigned>(v);
}

// Run f, mapping every exception to an error class and message naming what.
template <class F> int guarded(const char *what, struct st_error *err, F f)
{
	try {
		return f();
	} catch (const std::bad_alloc &) {
		return st_error_set(err, ST_ERR_NOMEM, "clip: out of memory in %s", what);
	} catch (const ClipperLib::clipperException &e) {
		return st_error_set(err, ST_ERR_RANGE,
				    "clip: %s refused the input (%s); coordinates must stay "
				    "within +-4.6e18 nm",
				    what, e.what());
	} catch (const std::exception &e) {
		return st_error_set(err, ST_ERR_INTERNAL, "clip: %s failed: %s", what, e.what());
	} catch (...) {
		return st_error_set(err, ST_ERR_INTERNAL, "clip: %s failed with an unknown exception",
				    what);
	}
}

int bad_enum(struct st_error *err, const char *what, const char *kind, int value)
{
	return st_error_set(err, ST_ERR_ARG, "clip: %s got an invalid %s (%d)", what, kind, value);
}

bool offset_args_ok(const char *what, enum clip_join join, double delta, double miter_limit,
		    double arc_tolerance, struct st_error *err)
{
	if (raw(join) >= CLIP_JOINS) {
		bad_enum(err, what, "join type", (int)raw(join));
		return false;
	}
	if (!(delta == delta) || delta > 4e18 || delta < -4e18) {
		st_error_set(err, ST_ERR_ARG, "clip: %s got offset distance %g nm", what, delta);
		return false;
	}
	if (join == CLIP_JOIN_MITER && !(miter_limit >= 2.0)) {
		st_error_set(err, ST_ERR_ARG, "clip: %s needs a miter limit >= 2, got %g", what,
			     miter_limit);
		return false;
	}
	if (join == CLIP_JOIN_ROUND && !(arc_tolerance > 0.0)) {
		st_error_set(err, ST_ERR_ARG, "clip: %s needs an arc tolerance > 0 nm, got %g",
			     what, arc_tolerance);
		return false;
	}
	return true;
}

ClipperLib::ClipperOffset make_offsetter(enum clip_join join, double miter_limit,
					 double arc_tolerance)
{
	// Clipper ignores the unused parameter of the other join types.
	return ClipperLib::ClipperOffset(join == CLIP_JOIN_MITER ? miter_limit : 2.0,
					 join == CLIP_JOIN_ROUND ? arc_tolerance : 0.25);
}

} // namespace

// A locator: the paths as Clipper paths, each with its bounding box.
struct clip_locator {
	Paths paths;
	std::vector<int64_t> box; // x0, y0, x1, y1 per path
};

extern "C" {

int clip_paths_add(struct clip_paths *ps, const int64_t *xy, size_t npts, struct st_error *err)
{
	if (!ps || (npts && !xy))
		return st_error_set(err, ST_ERR_ARG, "clip: clip_paths_add got no %s",
				    ps ? "coordinates" : "path set");
	if (!npts)
		return 0;
	return guarded("clip_paths_add", err, [&] {
		push_path(ps, xy, npts);
		return 0;
	});
}

int clip_paths_append(struct clip_paths *dst, const struct clip_paths *src, struct st_error *err)
{
	if (!dst || !src || dst == src)
		return st_error_set(err, ST_ERR_ARG,
				    "clip: clip_paths_append needs two distinct path sets");
	return guarded("clip_paths_append", err, [&] {
		for (size_t i = 0; i < src->n; i++)
			push_path(dst, clip_path_xy(src, i), clip_path_len(src, i));
		return 0;
	});
}

void clip_paths_clear(struct clip_paths *ps)
{
	if (ps)
		ps->n = 0;
}

void clip_paths_free(struct clip_paths *ps)
{
	if (!ps)
		return;
	std::free(ps->start);
	std::free(ps->xy);
	std::memset(ps, 0, sizeof(*ps));
}

void clip_expolys_clear(struct clip_expolys *ex)
{
	if (!ex)
		return;
	clip_paths_clear(&ex->paths);
	ex->n = 0;
}

void clip_expolys_free(struct clip_expolys *ex)
{
	if (!ex)
		return;
	clip_paths_free(&ex->paths);
	std::free(ex->first);
	std::memset(ex, 0, sizeof(*ex));
}

int clip_expolys_get(const struct clip_expolys *ex, size_t i, struct clip_paths *out,
		     struct st_error *err)
{
	if (!ex || !out || i >= ex->n || out == &ex->paths)
		return st_error_set(err, ST_ERR_ARG, "clip: no expolygon %zu in a set of %zu", i,
				    ex ? ex->n : 0);
	return guarded("clip_expolys_get", err, [&] {
		clip_paths_clear(out);
		for (size_t p = ex->first[i]; p < ex->first[i + 1]; p++)
			push_path(out, clip_path_xy(&ex->paths, p), clip_path_len(&ex->paths, p));
		return 0;
	});
}

int clip_boolean(enum clip_op op, const struct clip_paths *subject, const struct clip_paths *clip,
		 enum clip_fill fill, struct clip_paths *out, struct st_error *err)
{
	if (raw(op) >= CLIP_OPS)
		return bad_enum(err, "clip_boolean", "operation", (int)raw(op));
	if (raw(fill) >= CLIP_FILLS)
		return bad_enum(err, "clip_boolean", "fill rule", (int)raw(fill));
	if (!subject || !out)
		return st_error_set(err, ST_ERR_ARG, "clip: clip_boolean needs a subject and out");
	return guarded("clip_boolean", err, [&] {
		ClipperLib::Clipper c;
		Paths result;
		// Clipper's Execute fails when it was given no edge at all: that
		// is the empty set, not an error.
		bool any = c.AddPaths(to_paths(subject), ClipperLib::ptSubject, true);
		any = c.AddPaths(to_paths(clip), ClipperLib::ptClip, true) || any;
		if (any && !c.Execute(clip_types[op], result, fill_types[fill], fill_types[fill]))
			return st_error_set(err, ST_ERR_INTERNAL, "clip: Clipper refused a boolean");
		from_paths(result, out);
		return 0;
	});
}

int clip_boolean_ex(enum clip_op op, const struct clip_paths *subject,
		    const struct clip_paths *clip, enum clip_fill fill, struct clip_expolys *out,
		    struct st_error *err)
{
	if (raw(op) >= CLIP_OPS)
		return bad_enum(err, "clip_boolean_ex", "operation", (int)raw(op));
	if (raw(fill) >= CLIP_FILLS)
		return bad_enum(err, "clip_boolean_ex", "fill rule", (int)raw(fill));
	if (!subject || !out || subject == &out->paths || clip == &out->paths)
		return st_error_set(err, ST_ERR_ARG,
				    "clip: clip_boolean_ex needs a subject and a distinct out");
	return guarded("clip_boolean_ex", err, [&] {
		// The operation into plain paths, then a union of those into the
		// tree: Clipper re-tests the owner of every output contour after
		// each join while it builds a tree, which took seconds on unions
		// of a few hundred overlapping islands; the second pass has
		// nothing left to join and nests the clean contours in
		// milliseconds.
		ClipperLib::Clipper c, nest;
		ClipperLib::PolyTree tree;
		Paths flat;
		bool any = c.AddPaths(to_paths(subject), ClipperLib::ptSubject, true);
		any = c.AddPaths(to_paths(clip), ClipperLib::ptClip, true) || any;
		if (any && !c.Execute(clip_types[op], flat, fill_types[fill], fill_types[fill]))
			return st_error_set(err, ST_ERR_INTERNAL, "clip: Clipper refused a boolean");
		if (nest.AddPaths(flat, ClipperLib::ptSubject, true) &&
		    !nest.Execute(ClipperLib::ctUnion, tree, ClipperLib::pftNonZero,
				  ClipperLib::pftNonZero))
			return st_error_set(err, ST_ERR_INTERNAL, "clip: Clipper refused a boolean");
		from_tree(tree, out);
		return 0;
	});
}

int clip_lines(enum clip_op op, const struct clip_paths *lines, const struct clip_paths *polys,
	       enum clip_fill fill, struct clip_paths *out, struct st_error *err)
{
	if (raw(op) != CLIP_INTERSECTION && raw(op) != CLIP_DIFFERENCE)
		return bad_enum(err, "clip_lines", "operation (only intersection, difference)",
				(int)raw(op));
	if (raw(fill) >= CLIP_FILLS)
		return bad_enum(err, "clip_lines", "fill rule", (int)raw(fill));
	if (!lines || !out || out == lines || out == polys)
		return st_error_set(err, ST_ERR_ARG,
				    "clip: clip_lines needs lines and a distinct out");
	return guarded("clip_lines", err, [&] {
		ClipperLib::Clipper c;
		ClipperLib::PolyTree tree;
		Paths open;
		bool any = c.AddPaths(to_paths(lines), ClipperLib::ptSubject, false);
		any = c.AddPaths(to_paths(polys), ClipperLib::ptClip, true) || any;
		if (any && !c.Execute(clip_types[op], tree, fill_types[fill], fill_types[fill]))
			return st_error_set(err, ST_ERR_INTERNAL, "clip: Clipper refused to clip lines");
		ClipperLib::OpenPathsFromPolyTree(tree, open);
		from_paths(open, out);
		return 0;
	});
}

int clip_offset(const struct clip_paths *in, double delta, enum clip_join join,
		double miter_limit, double arc_tolerance, struct clip_paths *out,
		struct st_error *err)
{
	if (!offset_args_ok("clip_offset", join, delta, miter_limit, arc_tolerance, err))
		return err ? err->code : ST_ERR_ARG;
	if (!in || !out)
		return st_error_set(err, ST_ERR_ARG, "clip: clip_offset needs in and out");
	return guarded("clip_offset", err, [&] {
		ClipperLib::ClipperOffset o = make_offsetter(join, miter_limit, arc_tolerance);
		Paths result;
		o.AddPaths(to_paths(in), join_types[join], ClipperLib::etClosedPolygon);
		o.Execute(result, delta);
		from_paths(result, out);
		return 0;
	});
}

int clip_offset_ex(const struct clip_paths *in, double delta, enum clip_join join,
		   double miter_limit, double arc_tolerance, struct clip_expolys *out,
		   struct st_error *err)
{
	if (!offset_args_ok("clip_offset_ex", join, delta, miter_limit, arc_tolerance, err))
		return err ? err->code : ST_ERR_ARG;
	if (!in || !out || in == &out->paths)
		return st_error_set(err, ST_ERR_ARG, "clip: clip_offset_ex needs in and a distinct out");
	return guarded("clip_offset_ex", err, [&] {
		ClipperLib::ClipperOffset o = make_offsetter(join, miter_limit, arc_tolerance);
		ClipperLib::PolyTree tree;
		o.AddPaths(to_paths(in), join_types[join], ClipperLib::etClosedPolygon);
		o.Execute(tree, delta);
		from_tree(tree, out);
		return 0;
	});
}

int clip_offset_open(const struct clip_paths *lines, double delta, enum clip_join join,
		     enum clip_end end, double miter_limit, double arc_tolerance,
		     struct clip_paths *out, struct st_error *err)
{
	if (!offset_args_ok("clip_offset_open", join, delta, miter_limit, arc_tolerance, err))
		return err ? err->code : ST_ERR_ARG;
	if (raw(end) >= CLIP_ENDS)
		return bad_enum(err, "clip_offset_open", "end type", (int)raw(end));
	if (end == CLIP_END_ROUND && !(arc_tolerance > 0.0))
		return st_error_set(err, ST_ERR_ARG,
				    "clip: clip_offset_open needs an arc tolerance > 0 nm for "
				    "round ends, got %g",
				    arc_tolerance);
	if (!lines || !out)
		return st_error_set(err, ST_ERR_ARG, "clip: clip_offset_open needs lines and out");
	return guarded("clip_offset_open", err, [&] {
		ClipperLib::ClipperOffset o(join == CLIP_JOIN_MITER ? miter_limit : 2.0,
					    arc_tolerance > 0.0 ? arc_tolerance : 0.25);
		Paths result;
		o.AddPaths(to_paths(lines), join_types[join], end_types[end]);
		o.Execute(result, delta);
		from_paths(result, out);
		return 0;
	});
}

int clip_sweep(const struct clip_paths *lines, const double *delta, double arc_tolerance,
	       struct clip_paths *out, struct st_error *err)
{
	if (!lines || !out || out == lines || (lines->n && !delta))
		return st_error_set(err, ST_ERR_ARG, "clip: clip_sweep needs lines, widths and a distinct out");
	if (!(arc_tolerance > 0.0))
		return st_error_set(err, ST_ERR_ARG, "clip: clip_sweep needs an arc tolerance > 0 nm, got %g",
				    arc_tolerance);
	for (size_t i = 0; i < lines->n; i++)
		if (!(delta[i] > 0.0) || delta[i] > 4e18)
			return st_error_set(err, ST_ERR_ARG, "clip: clip_sweep got bead half-width %g nm for path %zu",
					    delta[i], i);
	return guarded("clip_sweep", err, [&] {
		// One ClipperOffset per distinct delta: Execute takes one delta.
		std::map<double, Paths> groups;
		for (size_t i = 0; i < lines->n; i++) {
			Path p = to_path(clip_path_xy(lines, i), clip_path_len(lines, i));
			if (p.empty())
				continue;
			if (p.size() == 1)
				p.push_back(p[0]); // Clipper offsets a 2-point zero-length line as a disk
			groups[delta[i]].push_back(std::move(p));
		}
		ClipperLib::Clipper c;
		bool any = false;
		for (auto &g : groups) {
			ClipperLib::ClipperOffset o(2.0, arc_tolerance);
			Paths swept;
			o.AddPaths(g.second, ClipperLib::jtRound, ClipperLib::etOpenRound);
			o.Execute(swept, g.first);
			any = c.AddPaths(swept, ClipperLib::ptSubject, true) || any;
		}
		Paths result;
		if (any && !c.Execute(ClipperLib::ctUnion, result, ClipperLib::pftNonZero,
				      ClipperLib::pftNonZero))
			return st_error_set(err, ST_ERR_INTERNAL, "clip: Clipper refused to unite beads");
		from_paths(result, out);
		return 0;
	});
}

int clip_simplify(const struct clip_paths *in, enum clip_fill fill, struct clip_paths *out,
		  struct st_error *err)
{
	if (raw(fill) >= CLIP_FILLS)
		return bad_enum(err, "clip_simplify", "fill rule", (int)raw(fill));
	if (!in || !out)
		return st_error_set(err, ST_ERR_ARG, "clip: clip_simplify needs in and out");
	return guarded("clip_simplify", err, [&] {
		Paths result;
		ClipperLib::SimplifyPolygons(to_paths(in), result, fill_types[fill]);
		from_paths(result, out);
		return 0;
	});
}

int clip_clean(struct clip_paths *ps, double distance, struct st_error *err)
{
	if (!ps || !(distance >= 0.0))
		return st_error_set(err, ST_ERR_ARG, "clip: clip_clean needs paths and a distance >= 0");
	return guarded("clip_clean", err, [&] {
		Paths p = to_paths(ps), kept;
		ClipperLib::CleanPolygons(p, distance);
		for (Path &q : p)
			if (q.size() >= 3)
				kept.push_back(q);
		from_paths(kept, ps);
		return 0;
	});
}

int clip_expolys_clean(struct clip_expolys *ex, double distance, struct st_error *err)
{
	if (!ex || !(distance >= 0.0))
		return st_error_set(err, ST_ERR_ARG,
				    "clip: clip_expolys_clean needs polygons and a distance >= 0");
	return guarded("clip_expolys_clean", err, [&] {
		struct clip_expolys kept = {};
		try {
			for (size_t i = 0; i < ex->n; i++) {
				bool outer = true;
				for (size_t p = ex->first[i]; p < ex->first[i + 1]; p++) {
					Path q = to_path(clip_path_xy(&ex->paths, p),
							 clip_path_len(&ex->paths, p));
					ClipperLib::CleanPolygon(q, distance);
					if (q.size() < 3) {
						if (outer)
							break; /* the island is gone, holes and all */
						continue;
					}
					if (outer)
						open_expoly(&kept);
					push_path(&kept.paths, q);
					kept.first[kept.n] = kept.paths.n;
					outer = false;
				}
			}
		} catch (...) {
			clip_expolys_free(&kept);
			throw;
		}
		clip_expolys_free(ex);
		*ex = kept;
		return 0;
	});
}

int clip_area(const int64_t *xy, size_t npts, double *area, struct st_error *err)
{
	if (!area || (npts && !xy))
		return st_error_set(err, ST_ERR_ARG, "clip: clip_area needs a path and a result");
	*area = 0.0;
	return guarded("clip_area", err, [&] {
		*area = ClipperLib::Area(to_path(xy, npts));
		return 0;
	});
}

int clip_paths_area(const struct clip_paths *ps, double *area, struct st_error *err)
{
	if (!ps || !area)
		return st_error_set(err, ST_ERR_ARG, "clip: clip_paths_area needs paths and a result");
	*area = 0.0;
	return guarded("clip_paths_area", err, [&] {
		double sum = 0.0;
		for (size_t i = 0; i < ps->n; i++)
			sum += ClipperLib::Area(to_path(clip_path_xy(ps, i), clip_path_len(ps, i)));
		*area = sum;
		return 0;
	});
}

// clip_erosion_kept asks for this much more depth than r, nm: far beyond
// Clipper's rounding of an offset (1 nm), so a region it calls kept never
// comes out of the offset empty.
#define CLIP_KEPT_MARGIN_NM 1000.0

bool clip_erosion_kept(const struct clip_paths *ps, double r)
{
	double area = 0.0, strip = 0.0, turn = 0.0;

	if (!ps || !(r >= 0.0))
		return false;
	r += CLIP_KEPT_MARGIN_NM;
	for (size_t i = 0; i < ps->n; i++) {
		const int64_t *xy = clip_path_xy(ps, i);
		size_t n = clip_path_len(ps, i);
		for (size_t k = 0; k < n; k++) {
			const int64_t *a = xy + 2 * ((k + n - 1) % n), *b = xy + 2 * k,
				      *c = xy + 2 * ((k + 1) % n);
			double ux = (double)(b[0] - a[0]), uy = (double)(b[1] - a[1]);
			double vx = (double)(c[0] - b[0]), vy = (double)(c[1] - b[1]);
			double cross = ux * vy - uy * vx;
			area += ((double)b[0] * (double)c[1] - (double)c[0] * (double)b[1]) / 2.0;
			strip += std::hypot(vx, vy);
			if (cross < 0.0) // a right turn: reflex with the inside on the left
				turn += std::atan2(-cross, ux * vx + uy * vy);
		}
	}
	return area > strip * r + turn * r * r / 2.0;
}

int clip_point_in_polygon(int64_t x, int64_t y, const int64_t *xy, size_t npts, int *where,
			  struct st_error *err)
{
	if (!where || (npts && !xy))
		return st_error_set(err, ST_ERR_ARG,
				    "clip: clip_point_in_polygon needs a path and a result");
	*where = 0;
	return guarded("clip_point_in_polygon", err, [&] {
		*where = ClipperLib::PointInPolygon(IntPoint(x, y), to_path(xy, npts));
		return 0;
	});
}

} // extern "C"

extern "C" {

struct clip_locator *clip_locator_new(const struct clip_paths *ps, struct st_error *err)
{
	struct clip_locator *loc = nullptr;

	if (!ps) {
		st_error_set(err, ST_ERR_ARG, "clip: clip_locator_new needs paths");
		return nullptr;
	}
	int rc = guarded("clip_locator_new", err, [&] {
		std::unique_ptr<clip_locator> l(new clip_locator);
		l->paths = to_paths(ps);
		l->box.reserve(4 * l->paths.size());
		for (const Path &p : l->paths) {
			int64_t x0 = INT64_MAX, y0 = INT64_MAX, x1 = INT64_MIN, y1 = INT64_MIN;
			for (const IntPoint &q : p) {
				x0 = q.X < x0 ? q.X : x0;
				y0 = q.Y < y0 ? q.Y : y0;
				x1 = q.X > x1 ? q.X : x1;
				y1 = q.Y > y1 ? q.Y : y1;
			}
			l->box.insert(l->box.end(), {x0, y0, x1, y1});
		}
		loc = l.release();
		return 0;
	});
	return rc ? nullptr : loc;
}

bool clip_locator_inside(const struct clip_locator *loc, int64_t x, int64_t y)
{
	int parity = 0;

	if (!loc)
		return false;
	for (size_t i = 0; i < loc->paths.size(); i++) {
		const int64_t *b = &loc->box[4 * i];
		// Outside the closed box no edge is crossed or touched: Clipper
		// would answer 0 (outside) without any arithmetic.
		if (x < b[0] || x > b[2] || y < b[1] || y > b[3])
			continue;
		int where = ClipperLib::PointInPolygon(IntPoint(x, y), loc->paths[i]);
		if (where < 0)
			return true;
		parity ^= where;
	}
	return parity != 0;
}

void clip_locator_free(struct clip_locator *loc)
{
	delete loc;
}

} // extern "C"
