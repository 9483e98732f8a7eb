/*
 * meshio.c - the public entry points of meshio.h: open the input, detect its
 * format and hand it to the right reader (stlio.c, objoff.c, threemf.c).
 *
 * Detection, in order: binary STL when the size is exactly 84 + 50 * count
 * (whatever the header says, "solid" included); 3MF when the bytes open
 * like a zip archive (the reader then looks for the 3D model part in it);
 * ASCII STL when the text
 * starts with "solid"; OFF when the first keyword is OFF (or COFF, NOFF,
 * CNOFF); OBJ when it is an OBJ statement or the text opens with comments.
 * The extension only chooses between messages for content that fits none.
 */
#include "meshio_impl.h"

#include <errno.h>
#include <stdlib.h>
#include <string.h>
#include <sys/stat.h>

/* How much of the first window is checked for binary bytes. */
#define TEXT_PROBE 512

/* 1 if the file name ends in "." + ext, ignoring ASCII case. */
static bool has_extension(const char *name, const char *ext)
{
	const char *dot = strrchr(name, '.');

	return dot && !strchr(dot, '/') && mio_keyword(dot + 1, ext);
}

/* True if p[0..n) holds no bytes that text never contains. */
static bool looks_like_text(const unsigned char *p, size_t n)
{
	for (size_t i = 0; i < n; i++) {
		unsigned char c = p[i];
		if ((c < 0x20 && c != '\t' && c != '\n' && c != '\r' && c != '\f' && c != '\v') ||
		    c == 0x7f)
			return false;
	}
	return true;
}

/* A zip archive's first bytes: a local file header, or the end record of an empty one. */
static bool zip_signature(const unsigned char *p, size_t n)
{
	return n >= 4 && (!memcmp(p, "PK\x03\x04", 4) || !memcmp(p, "PK\x05\x06", 4));
}

/* Magic numbers of common non-mesh files (PNG, JPEG, GIF, gzip, ELF, PDF). */
static bool foreign_signature(const unsigned char *p, size_t n)
{
	static const struct {
		const char *magic;
		size_t len;
	} sig[] = {
	    {"\x89PNG\r\n\x1a\n", 8},
	    {"\xff\xd8\xff", 3},
	    {"GIF8", 4},
	    {"\x1f\x8b", 2},
	    {"\x7f"
	     "ELF",
	     4},
	    {"%PDF-", 5},
	};

	for (size_t i = 0; i < sizeof(sig) / sizeof(sig[0]); i++)
		if (n >= sig[i].len && !memcmp(p, sig[i].magic, sig[i].len))
			return true;
	return false;
}

/*
 * First keyword of a text window: skips a UTF-8 BOM, white space and '#'
 * comment lines.  Returns its length (0 if none) and sets *comment if a
 * comment line came first.
 */
static size_t first_keyword(const unsigned char *p, size_t n, const unsigned char **kw,
			    bool *comment)
{
	size_t i = 0, start;

	*comment = false;
	if (n >= 3 && !memcmp(p, "\xef\xbb\xbf", 3))
		i = 3;
	for (;;) {
		while (i < n && (p[i] == ' ' || p[i] == '\t' || p[i] == '\r' || p[i] == '\n' ||
				 p[i] == '\f' || p[i] == '\v'))
			i++;
		if (i >= n)
			return 0;
		if (p[i] != '#')
			break;
		*comment = true;
		while (i < n && p[i] != '\n')
			i++;
	}
	start = i;
	while (i < n && p[i] > ' ' && p[i] != 0x7f && p[i] != '#')
		i++;
	*kw = p + start;
	return i - start;
}

/* Exact (case-sensitive) match of a window keyword with word. */
static bool keyword_is(const unsigned char *kw, size_t len, const char *word)
{
	return len == strlen(word) && !memcmp(kw, word, len);
}

/* The OFF headers we read: plain, with colours, with normals, or both. */
static bool off_keyword(const unsigned char *kw, size_t len)
{
	return keyword_is(kw, len, "OFF") || keyword_is(kw, len, "COFF") ||
	       keyword_is(kw, len, "NOFF") || keyword_is(kw, len, "CNOFF");
}

/* Statements an OBJ file commonly opens with. */
static bool obj_keyword(const unsigned char *kw, size_t len)
{
	static const char *const words[] = {"v",      "vt",	"vn",	  "vp",	   "f",	 "l",
					    "p",      "o",	"g",	  "s",	   "mg", "usemtl",
					    "mtllib", "cstype", "maplib", "usemap"};

	for (size_t i = 0; i < sizeof(words) / sizeof(words[0]); i++)
		if (keyword_is(kw, len, words[i]))
			return true;
	return false;
}

/* "solid" then white space or the end: the opening of an ASCII STL. */
static bool starts_with_solid(const unsigned char *p, size_t n)
{
	const unsigned char *kw;
	bool comment;
	size_t len = first_keyword(p, n, &kw, &comment);

	static const char solid_word[] = "solid";

	if (comment || len != 5)
		return false;
	for (size_t i = 0; i < 5; i++)
		if ((kw[i] | 0x20) != solid_word[i])
			return false;
	return true;
}

/* The one message for content that fits no supported format. */
static int not_a_mesh(struct mio_src *s)
{
	if (has_extension(s->name, "3mf"))
		return mio_err(s, ST_ERR_PARSE,
			       "does not start like a zip archive, so it is not a 3MF file");
	return mio_err(s, ST_ERR_PARSE,
		       "not a mesh file (expected binary or ASCII STL, OBJ, OFF or 3MF)");
}

/* Decide the format of s from its first window; see the file comment. */
static int detect(struct mio_src *s, enum meshio_format *fmt)
{
	const unsigned char *p = s->p, *kw;
	size_t n = (size_t)(s->end - s->p), len;
	bool text = looks_like_text(p, n < TEXT_PROBE ? n : TEXT_PROBE);
	bool head_text = looks_like_text(p, n < 84 ? n : 84);
	bool solid = starts_with_solid(p, n), comment;

	if (stlio_binary_size_matches(s)) {
		*fmt = MESHIO_STL_BINARY;
		return 0;
	}
	if (zip_signature(p, n)) {
		*fmt = MESHIO_3MF;
		return 0;
	}
	if (foreign_signature(p, n))
		return not_a_mesh(s);
	if (solid && head_text) {
		*fmt = MESHIO_STL_ASCII;
		return 0;
	}
	if (!text) {
		/* A binary STL whose size is wrong: say so, with the numbers. */
		if (solid || has_extension(s->name, "stl"))
			return stlio_binary_size_error(s);
		return not_a_mesh(s);
	}
	len = first_keyword(p, n, &kw, &comment);
	if (len && off_keyword(kw, len)) {
		*fmt = MESHIO_OFF;
		return 0;
	}
	if ((len && obj_keyword(kw, len)) || (!len && comment) || has_extension(s->name, "obj")) {
		*fmt = MESHIO_OBJ;
		return 0;
	}
	if (has_extension(s->name, "off")) {
		*fmt = MESHIO_OFF;
		return 0;
	}
	return not_a_mesh(s);
}

/* Read s (positioned at its start) in format fmt, detecting it if AUTO. */
static int read_source(struct mio_src *s, enum meshio_format fmt, struct mesh **out,
		       struct meshio_info *info)
{
	struct meshio_info got = {.items = 1, .meshes = 1, .objects = 1};
	long avail;
	int rc;

	if (s->size == 0)
		return mio_err(s, ST_ERR_PARSE, "empty file");
	avail = mio_fill(s);
	if (avail < 0)
		return mio_read_error(s, 0);
	if (avail == 0)
		return mio_err(s, ST_ERR_PARSE, "empty file");
	if (fmt == MESHIO_AUTO) {
		rc = detect(s, &fmt);
		if (rc)
			return rc;
	}
	switch (fmt) {
	case MESHIO_STL_BINARY:
		rc = stlio_read_binary(s, out);
		break;
	case MESHIO_STL_ASCII:
		rc = stlio_read_ascii(s, out);
		break;
	case MESHIO_OBJ:
		rc = objoff_read_obj(s, out);
		break;
	case MESHIO_OFF:
		rc = objoff_read_off(s, out);
		break;
	case MESHIO_3MF:
		rc = threemf_read(s, out, &got);
		break;
	default:
		rc = mio_err(s, ST_ERR_ARG, "unknown mesh format %d", (int)fmt);
		break;
	}
	got.format = fmt;
	if (rc == 0 && info)
		*info = got;
	return rc;
}

/* fmt is one of the enum values (callers may cast anything). */
static bool format_valid(enum meshio_format fmt)
{
	return fmt == MESHIO_AUTO || fmt == MESHIO_STL_BINARY || fmt == MESHIO_STL_ASCII ||
	       fmt == MESHIO_OBJ || fmt == MESHIO_OFF || fmt == MESHIO_3MF;
}

/* Open path for reading into s (regular files only: sizes must be known). */
static int open_file(struct mio_src *s, const char *path, struct st_error *err)
{
	struct stat st;
	int rc;

	memset(s, 0, sizeof(*s));
	s->name = path;
	s->err = err;
	s->f = fopen(path, "rb");
	if (!s->f)
		return mio_err(s, ST_ERR_IO, "cannot open: %s", strerror(errno));
	if (fstat(fileno(s->f), &st)) {
		rc = mio_err(s, ST_ERR_IO, "cannot stat: %s", strerror(errno));
		goto out_close;
	}
	if (S_ISDIR(st.st_mode)) {
		rc = mio_err(s, ST_ERR_IO, "is a directory, not a mesh file");
		goto out_close;
	}
	if (!S_ISREG(st.st_mode)) {
		/* Size arithmetic needs the size up front: no pipes or devices. */
		rc = mio_err(s, ST_ERR_IO, "not a regular file; save the mesh to a file first");
		goto out_close;
	}
	s->size = (uint64_t)st.st_size;
	return 0;
out_close:
	fclose(s->f);
	s->f = NULL;
	return rc;
}

int meshio_read_info(const char *path, enum meshio_format fmt, struct mesh **out,
		     struct meshio_info *info, struct st_error *err)
{
	struct mio_src s;
	int rc;

	if (out)
		*out = NULL;
	if (!path || !out || !format_valid(fmt))
		return st_error_set(err, ST_ERR_ARG,
				    "meshio_read: no path, no output or bad format");
	if ((rc = open_file(&s, path, err)))
		return rc;
	s.chunk = malloc(MIO_CHUNK);
	if (!s.chunk) {
		rc = mio_err(&s, ST_ERR_NOMEM, "out of memory for the read buffer");
		goto out_close;
	}
	s.p = s.end = s.chunk;
	rc = read_source(&s, fmt, out, info);
	free(s.chunk);
out_close:
	fclose(s.f);
	return rc;
}

int meshio_read(const char *path, enum meshio_format fmt, struct mesh **out,
		enum meshio_format *detected, struct st_error *err)
{
	struct meshio_info info;
	int rc = meshio_read_info(path, fmt, out, &info, err);

	if (rc == 0 && detected)
		*detected = info.format;
	return rc;
}

int meshio_read_buffer_info(const void *buf, size_t len, const char *name,
			    enum meshio_format fmt, struct mesh **out, struct meshio_info *info,
			    struct st_error *err)
{
	struct mio_src s;

	if (out)
		*out = NULL;
	if ((!buf && len) || !out || !format_valid(fmt))
		return st_error_set(err, ST_ERR_ARG,
				    "meshio_read_buffer: no buffer, no output or bad format");
	memset(&s, 0, sizeof(s));
	s.name = name ? name : "(buffer)";
	s.err = err;
	if (len) {
		s.p = buf;
		s.end = s.p + len;
	}
	s.size = len;
	return read_source(&s, fmt, out, info);
}

int meshio_read_buffer(const void *buf, size_t len, const char *name, enum meshio_format fmt,
		       struct mesh **out, enum meshio_format *detected, struct st_error *err)
{
	struct meshio_info info;
	int rc = meshio_read_buffer_info(buf, len, name, fmt, out, &info, err);

	if (rc == 0 && detected)
		*detected = info.format;
	return rc;
}

int meshio_3mf_config(const char *path, char **text, struct st_error *err)
{
	struct mio_src s;
	int rc;

	if (text)
		*text = NULL;
	if (!path || !text)
		return st_error_set(err, ST_ERR_ARG, "meshio_3mf_config: no path or no output");
	if ((rc = open_file(&s, path, err)))
		return rc;
	rc = threemf_text(&s, MESHIO_3MF_CONFIG_ENTRY, text);
	fclose(s.f);
	return rc;
}

int meshio_3mf_layer_profile(const char *path, size_t object, double **zh, size_t *pairs,
			     size_t *profiles, struct st_error *err)
{
	struct mio_src s;
	int rc;

	if (zh)
		*zh = NULL;
	if (pairs)
		*pairs = 0;
	if (profiles)
		*profiles = 0;
	if (!path || !zh || !pairs)
		return st_error_set(err, ST_ERR_ARG, "meshio_3mf_layer_profile: no path or no output");
	if ((rc = open_file(&s, path, err)))
		return rc;
	rc = threemf_layer_profile(&s, object, zh, pairs, profiles);
	fclose(s.f);
	return rc;
}

int meshio_write_stl(const char *path, const struct mesh *m, enum meshio_format fmt,
		     struct st_error *err)
{
	return stlio_write(path, m, fmt, err);
}
