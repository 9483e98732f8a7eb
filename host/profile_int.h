/*
 * profile_int.h - what the profile modules share (host/profile*.c); nothing
 * outside them includes it.  The public contract is profile.h.
 *
 *   profile.c        loading (through ini.h), freeing, raw key access
 *   profile_bind.c   the binding of each declared setting
 *                    (slicer/settings.h) to its struct profile field and
 *                    to the slicer_config field it is copied into, and
 *                    the declared defaults
 *   profile_keys.c   key typing: the parsers of every value type
 *   profile_check.c  checks between keys, and the slicer's own check
 *   profile_find.c   search directories, NAME lookup, listing
 *   profile_out.c    profile_write and profile_to_json
 */
#ifndef STRATUM_HOST_PROFILE_INT_H
#define STRATUM_HOST_PROFILE_INT_H

#include "profile.h"
#include "settings.h"

/* One key = value line of the file. */
struct profile_kv {
	char *key;
	char *value; /* escapes decoded */
	int line;
	const char *file; /* where it was set (one of files[]), NULL: the profile's path */
};

struct profile_keys {
	struct profile_kv *kv;
	size_t count, cap;
	char **files; /* the files and options the keys came from (owned) */
	size_t nfiles, files_cap;
};

/* How a key is parsed and where it is stored (its range is declared in settings.c). */
enum key_type {
	KT_STRING,	 /* const char * */
	KT_FIRST_STRING, /* const char *: the first of "a";"b" (per filament) */
	KT_DOUBLE,	 /* double */
	KT_INT,		 /* int */
	KT_BOOL,	 /* bool, 0/1 */
	KT_EX_DOUBLE,	 /* double[PROFILE_MAX_EXTRUDERS], one per extruder */
	KT_EX_INT,	 /* int[PROFILE_MAX_EXTRUDERS] */
	KT_EX_POINT,	 /* struct profile_point[PROFILE_MAX_EXTRUDERS], "XxY" */
	KT_FIRST_DOUBLE, /* double; a list is accepted, its first value used */
	KT_FIRST_INT,	 /* int; likewise */
	KT_FIRST_BOOL,	 /* bool; likewise */
	KT_FIRST_HEIGHT, /* first_layer_height: mm or % of layer_height */
	KT_WIDTH,	 /* extrusion_width: mm or % of layer_height, 0 = auto */
	KT_NUM_PCT,	 /* struct profile_pct: a number (mm/s, mm) or % */
	KT_DENSITY,	 /* double: N% or a fraction 0-1 (fill_density, ironing_flowrate) */
	KT_PROTOCOL,	 /* enum profile_protocol */
	KT_FLAVOR,	 /* enum profile_flavor */
	KT_BAUD,	 /* long, a standard rate */
	KT_USB,		 /* usb_ids */
	KT_BED,		 /* bed_shape */
	KT_CHOICE,	 /* const char *: one of the declared names (fill_pattern ...) */
	KT_HOME,	 /* enum profile_home */
	KT_EXTRUDERS,	 /* extruder_count */
};

/* What a profile field and the slicer_config field it is copied into hold. */
enum cfg_type {
	CT_NONE,   /* no slicer field: the slicer does not take the key, or takes it
		    * computed (profile_slicer.c) */
	CT_DOUBLE, /* double (or an array's first) */
	CT_INT,	   /* int (or an array's first); copied into an int or a double */
	CT_BOOL,   /* bool */
	CT_STRING, /* const char * */
};

/* A declared setting bound to its field, and to the slicer's (profile_bind.c). */
struct key_def {
	const char *key;
	enum key_type type;
	size_t off;		      /* offsetof(struct profile, field) */
	size_t cfg;		      /* offsetof(struct slicer_config, field) */
	enum cfg_type held, cfg_type; /* the two fields' types; cfg_type CT_NONE: not copied */
};

/* Loading state: the profile being filled and where errors go. */
struct loader {
	struct profile *p;
	const char *origin;
	struct st_error *err;
	const struct profile_kv *ec_kv; /* what set extruder_count, NULL = default */
	const char *ec_key;
};

/* State pass 2 keeps for percentages resolved once layer_height is known. */
struct pending {
	bool flh_pct, width_pct;
	double flh, width;
};

/* One comma-separated item of a list value. */
struct item {
	const char *s;
	size_t len;
};

/* The bound keys in declaration order; the declaration of one. */
const struct key_def *prof_defs(size_t *count);
const struct key_def *prof_find_def(const char *key);
const struct setting *prof_decl(const struct key_def *d);

char *prof_dup(const char *s, size_t len);

/*
 * prof_find_vendor - the printer preset called name (or its slug) in
 * PrusaSlicer's vendor bundles ($STRATUM_VENDOR_DIR, else PROFILE_VENDOR_DIR),
 * loaded with its default print and filament presets.  Returns 0 with *out,
 * 1 when no bundle has it, or the loader's error (profile_vendor.c).
 */
int prof_find_vendor(const char *name, struct profile **out, struct st_error *err);
void prof_trim(const char **s, size_t *len);
void prof_fmt_double(char *buf, size_t cap, double v);
struct profile_kv *prof_find_kv(const struct profile_keys *keys, const char *key);

/* "ORIGIN: line N: KEY: message" (line and key left out when kv and key are NULL). */
int prof_key_error(struct loader *L, const struct profile_kv *kv, const char *key, int code,
		   const char *fmt, ...) __attribute__((format(printf, 5, 6)));

/* Split a list value into at most cap trimmed items; the count or ST_ERR_PARSE. */
int prof_split_list(struct loader *L, const struct profile_kv *kv, struct item *items, size_t cap);

/* Type one key that the file sets (or a declared default, line 0). */
int prof_apply_key(struct loader *L, const struct key_def *d, const struct profile_kv *kv,
		   struct pending *pend);

/* Type every known key, apply the defaults that follow other keys, check (pass 2). */
int prof_apply_all(struct loader *L);

/* The declared defaults; sailfish: only those a sailfish printer changes. */
int prof_set_defaults(struct profile *p, bool sailfish);

/* Append one pair; takes ownership of key and value (frees them on failure). */
int prof_keys_add(struct profile_keys *keys, char *key, char *value, int line);

struct ini_entry;
/* One key = value line into keys, decoded; a key already there is refused. */
int prof_add_entry(struct profile_keys *keys, const struct ini_entry *e, const char *origin,
		   struct st_error *err);

/* A new empty profile named after origin (its base name without .ini). */
struct profile *prof_new(const char *origin, struct st_error *err);

/* Pass 2 over the keys already in p->keys; p is freed on error. */
int prof_finish(struct profile *p, const char *origin, struct profile **out,
		struct st_error *err);

/* The placeholder variables of a loaded profile (p->vars). */
int prof_build_vars(struct profile *p, struct st_error *err);

/* profile_slicer.c: whether firmware of flavour f takes G2/G3 arcs, so
 * arc_fitting is honoured (Marlin's ARC_SUPPORT is on by default;
 * RepRapFirmware has them; X3G and the others get lines). */
bool prof_flavor_arcs(enum profile_flavor f);

#endif /* STRATUM_HOST_PROFILE_INT_H */
