/*
 * journal.c - the job journal of `stratum print` (journal.h).
 */
#include "journal.h"

#include <errno.h>
#include <fcntl.h>
#include <jansson.h>
#include <math.h>
#include <openssl/evp.h>
#include <stdbool.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>
#include <sys/stat.h>
#include <time.h>
#include <unistd.h>

#include "st_file.h"

/* mkdir -p of path (modifies nothing else); 0 or -1 with errno. */
static int journal_mkdirs(char *path)
{
	for (char *p = path + 1; *p; p++) {
		if (*p != '/')
			continue;
		*p = '\0';
		if (mkdir(path, 0700) && errno != EEXIST) {
			*p = '/';
			return -1;
		}
		*p = '/';
	}
	return mkdir(path, 0700) && errno != EEXIST ? -1 : 0;
}

int journal_state_dir(char *out, size_t cap, const char *sub, const char *what,
		      struct st_error *err)
{
	const char *env = getenv(JOURNAL_ENV), *xdg = getenv("XDG_STATE_HOME");
	const char *home = getenv("HOME");
	int n;

	if (env && *env)
		n = snprintf(out, cap, "%s/%s", env, sub);
	else if (xdg && *xdg == '/')
		n = snprintf(out, cap, "%s/stratum/%s", xdg, sub);
	else if (home && *home)
		n = snprintf(out, cap, "%s/.local/state/stratum/%s", home, sub);
	else
		return st_error_set(err, ST_ERR_IO, "no state directory for the %s: set "
				    "HOME, XDG_STATE_HOME or " JOURNAL_ENV, what);
	if (n < 0 || (size_t)n >= cap)
		return st_error_set(err, ST_ERR_RANGE, "the state directory path is too long");
	if (journal_mkdirs(out))
		return st_error_set(err, ST_ERR_IO, "cannot create the %s directory %s: "
				    "%s", what, out, strerror(errno));
	return 0;
}

int journal_dir(char *out, size_t cap, struct st_error *err)
{
	return journal_state_dir(out, cap, "jobs", "job journal", err);
}

int journal_init(struct journal *j, struct st_error *err)
{
	char dir[JOURNAL_PATH_MAX - JOURNAL_ID_MAX - 8];
	time_t now = time(NULL);
	struct tm tm;
	int rc;

	memset(j, 0, sizeof(*j));
	if ((rc = journal_dir(dir, sizeof(dir), err)))
		return rc;
	gmtime_r(&now, &tm);
	snprintf(j->id, sizeof(j->id), "%04d%02d%02d-%02d%02d%02d-%ld", tm.tm_year + 1900,
		 tm.tm_mon + 1, tm.tm_mday, tm.tm_hour, tm.tm_min, tm.tm_sec, (long)getpid());
	snprintf(j->file, sizeof(j->file), "%s/%s.json", dir, j->id);
	snprintf(j->state, sizeof(j->state), "printing");
	j->layer = -1;
	j->z = NAN;
	return 0;
}

/* A number for JSON: null for NAN. */
static json_t *journal_real(double v)
{
	return isfinite(v) ? json_real(v) : json_null();
}

int journal_save(struct journal *j, struct st_error *err)
{
	json_t *o = json_object();
	struct st_file_out out;
	int rc;

	if (!o)
		return st_error_set(err, ST_ERR_NOMEM, "out of memory writing the job journal");
	j->updated = (int64_t)time(NULL);
	json_object_set_new(o, "id", json_string(j->id));
	json_object_set_new(o, "gcode", json_string(j->gcode));
	json_object_set_new(o, "sha256", json_string(j->sha256));
	json_object_set_new(o, "printer", json_string(j->printer));
	json_object_set_new(o, "port", json_string(j->port));
	json_object_set_new(o, "state", json_string(j->state));
	json_object_set_new(o, "lines", json_integer((json_int_t)j->lines));
	json_object_set_new(o, "last_line", json_integer((json_int_t)j->last_line));
	json_object_set_new(o, "layer", json_integer(j->layer));
	json_object_set_new(o, "z", journal_real(j->z));
	json_object_set_new(o, "tool_actual", journal_real(j->tool_actual));
	json_object_set_new(o, "tool_target", journal_real(j->tool_target));
	json_object_set_new(o, "bed_actual", journal_real(j->bed_actual));
	json_object_set_new(o, "bed_target", journal_real(j->bed_target));
	json_object_set_new(o, "updated", json_integer((json_int_t)j->updated));
	if ((rc = st_file_begin(&out, j->file, err)) == 0) {
		errno = 0;
		if (json_dumpf(o, out.f, JSON_INDENT(2) | JSON_PRESERVE_ORDER) ||
		    fputc('\n', out.f) == EOF)
			rc = st_file_fail(&out, err);
		else
			rc = st_file_commit(&out, err);
	}
	json_decref(o);
	if (rc)
		return st_error_set(err, rc, "cannot write the job journal: %s", err->msg);
	return 0;
}

/* Copy the string member key of o into out; false when missing. */
static bool journal_str(json_t *o, const char *key, char *out, size_t cap)
{
	const char *s = json_string_value(json_object_get(o, key));

	if (!s || strlen(s) >= cap)
		return false;
	memcpy(out, s, strlen(s) + 1);
	return true;
}

/* A number member of o, NAN when null or missing. */
static double journal_num(json_t *o, const char *key)
{
	json_t *v = json_object_get(o, key);

	return json_is_number(v) ? json_number_value(v) : NAN;
}

int journal_load(const char *job, struct journal *j, struct st_error *err)
{
	char dir[JOURNAL_PATH_MAX - JOURNAL_ID_MAX - 8];
	json_error_t je;
	json_t *o;
	int rc;

	memset(j, 0, sizeof(*j));
	if (strchr(job, '/') || strstr(job, ".json")) {
		snprintf(j->file, sizeof(j->file), "%s", job);
	} else {
		if ((rc = journal_dir(dir, sizeof(dir), err)))
			return rc;
		snprintf(j->file, sizeof(j->file), "%s/%s.json", dir, job);
	}
	if (access(j->file, R_OK))
		return st_error_set(err, ST_ERR_IO, "no job %s: %s: %s", job, j->file,
				    strerror(errno));
	o = json_load_file(j->file, 0, &je);
	if (!o)
		return st_error_set(err, ST_ERR_PARSE, "%s: line %d: not a job journal: %s",
				    j->file, je.line, je.text);
	if (!journal_str(o, "id", j->id, sizeof(j->id)) ||
	    !journal_str(o, "gcode", j->gcode, sizeof(j->gcode)) ||
	    !journal_str(o, "sha256", j->sha256, sizeof(j->sha256)) ||
	    !journal_str(o, "printer", j->printer, sizeof(j->printer)) ||
	    !journal_str(o, "port", j->port, sizeof(j->port)) ||
	    !journal_str(o, "state", j->state, sizeof(j->state)) ||
	    !json_is_integer(json_object_get(o, "last_line")) ||
	    !json_is_integer(json_object_get(o, "layer"))) {
		json_decref(o);
		return st_error_set(err, ST_ERR_PARSE, "%s: not a job journal (a key is missing "
				    "or has the wrong type)", j->file);
	}
	j->lines = (uint64_t)json_integer_value(json_object_get(o, "lines"));
	j->last_line = (uint64_t)json_integer_value(json_object_get(o, "last_line"));
	j->layer = (long)json_integer_value(json_object_get(o, "layer"));
	j->z = journal_num(o, "z");
	j->tool_actual = journal_num(o, "tool_actual");
	j->tool_target = journal_num(o, "tool_target");
	j->bed_actual = journal_num(o, "bed_actual");
	j->bed_target = journal_num(o, "bed_target");
	j->updated = (int64_t)json_integer_value(json_object_get(o, "updated"));
	json_decref(o);
	return 0;
}

int journal_sha256(const char *path, char hex[65], struct st_error *err)
{
	unsigned char buf[1 << 16], md[EVP_MAX_MD_SIZE];
	unsigned mdlen = 0;
	EVP_MD_CTX *ctx;
	FILE *f = fopen(path, "rb");
	size_t n;
	int rc = 0;

	if (!f)
		return st_error_set(err, ST_ERR_IO, "cannot open %s: %s", path, strerror(errno));
	ctx = EVP_MD_CTX_new();
	if (!ctx || EVP_DigestInit_ex(ctx, EVP_sha256(), NULL) != 1) {
		rc = st_error_set(err, ST_ERR_INTERNAL, "SHA-256 is not available (libcrypto)");
		goto out;
	}
	while ((n = fread(buf, 1, sizeof(buf), f)) > 0)
		if (EVP_DigestUpdate(ctx, buf, n) != 1) {
			rc = st_error_set(err, ST_ERR_INTERNAL, "SHA-256 of %s failed", path);
			goto out;
		}
	if (ferror(f)) {
		rc = st_error_set(err, ST_ERR_IO, "cannot read %s: %s", path, strerror(errno));
		goto out;
	}
	if (EVP_DigestFinal_ex(ctx, md, &mdlen) != 1 || mdlen != 32) {
		rc = st_error_set(err, ST_ERR_INTERNAL, "SHA-256 of %s failed", path);
		goto out;
	}
	for (unsigned i = 0; i < mdlen; i++)
		snprintf(hex + 2 * i, 3, "%02x", md[i]);
out:
	EVP_MD_CTX_free(ctx);
	fclose(f);
	return rc;
}
