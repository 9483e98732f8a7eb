/*
 * profile_find.c - where profiles are found: the search directories,
 * NAME lookup and listing (profile.h).
 */
#include "profile_int.h"
#include "st_append.h"
#include "st_grow.h"

#include <dirent.h>
#include <limits.h>
#include <stdlib.h>
#include <string.h>
#include <sys/stat.h>
#include <unistd.h>

/* Add dir to dirs unless it is empty, too long or already there. */
static void dirs_add(struct profile_dirs *dirs, const char *dir)
{
	if (!dir || !*dir || strlen(dir) >= PROFILE_PATH_MAX || dirs->count == PROFILE_MAX_DIRS)
		return;
	for (size_t i = 0; i < dirs->count; i++)
		if (!strcmp(dirs->path[i], dir))
			return;
	strcpy(dirs->path[dirs->count++], dir);
}

void profile_search_dirs(struct profile_dirs *dirs)
{
	char exe[PROFILE_PATH_MAX], cand[PROFILE_PATH_MAX + 32], real[PATH_MAX];
	ssize_t n;

	const char *xdg = getenv("XDG_CONFIG_HOME"), *home = getenv("HOME");

	dirs->count = 0;
	dirs_add(dirs, getenv("STRATUM_PRINTERS_DIR"));
	/* the user's own profiles (XDG base directories) */
	if ((xdg && *xdg) || (home && *home)) {
		snprintf(cand, sizeof(cand), "%s%s/stratum/printers", xdg && *xdg ? xdg : home,
			 xdg && *xdg ? "" : "/.config");
		struct stat st;
		if (stat(cand, &st) == 0 && S_ISDIR(st.st_mode))
			dirs_add(dirs, cand);
	}
	n = readlink("/proc/self/exe", exe, sizeof(exe) - 1);
	if (n > 0) {
		char *slash;

		exe[n] = '\0';
		slash = strrchr(exe, '/');
		if (slash) {
			*slash = '\0'; /* the executable's directory */
			/* PREFIX/bin/stratum: PREFIX/share/stratum/printers (make
			 * install, under any PREFIX and DESTDIR); else the source
			 * tree's, <exe dir>/../printers or <exe dir>/../../printers */
			static const char *const rel[] = {"../share/stratum/printers",
							  "../printers", "../../printers"};

			for (size_t up = 0; up < sizeof(rel) / sizeof(rel[0]); up++) {
				snprintf(cand, sizeof(cand), "%s/%s", exe, rel[up]);
				if (realpath(cand, real)) {
					struct stat st;
					if (stat(real, &st) == 0 && S_ISDIR(st.st_mode)) {
						dirs_add(dirs, real);
						break;
					}
				}
			}
		}
	}
	dirs_add(dirs, STRATUM_DATADIR);
}

/* A NAME is letters, digits, '.', '_', '-', not starting with '.'. */
static bool valid_name(const char *s)
{
	if (!*s || *s == '.')
		return false;
	for (; *s; s++)
		if (!(*s >= '0' && *s <= '9') && !(*s >= 'a' && *s <= 'z') && !(*s >= 'A' && *s <= 'Z') &&
		    *s != '.' && *s != '_' && *s != '-')
			return false;
	return true;
}

/* Does path name an existing regular file? */
static bool is_regular_file(const char *path)
{
	struct stat st;

	return stat(path, &st) == 0 && S_ISREG(st.st_mode);
}

int profile_find(const char *name_or_path, struct profile **out, struct st_error *err)
{
	struct profile_dirs dirs;
	char path[PROFILE_PATH_MAX + 300], looked[200];
	size_t len;

	if (!out)
		return st_error_set(err, ST_ERR_ARG, "profile_find: bad arguments");
	*out = NULL;
	if (!name_or_path || !*name_or_path)
		return st_error_set(err, ST_ERR_ARG,
				    "no printer given; name a profile ('stratum printers' lists "
				    "them) or a .ini file");
	len = strlen(name_or_path);
	if (strchr(name_or_path, '/') || (len >= 4 && !strcmp(name_or_path + len - 4, ".ini")))
		return profile_load_file(name_or_path, out, err);
	profile_search_dirs(&dirs);
	for (size_t i = 0; valid_name(name_or_path) && i < dirs.count; i++) {
		snprintf(path, sizeof(path), "%s/%s.ini", dirs.path[i], name_or_path);
		if (is_regular_file(path))
			return profile_load_file(path, out, err);
	}
	int rc = prof_find_vendor(name_or_path, out, err);
	if (rc <= 0)
		return rc;
	if (!valid_name(name_or_path))
		return st_error_set(err, ST_ERR_ARG,
				    "'%.64s' is neither a printer name (letters, digits, '.', '_' "
				    "and '-') nor a printer preset of PrusaSlicer's bundles; give a "
				    "file as a path ending in .ini",
				    name_or_path);
	looked[0] = '\0';
	for (size_t i = 0; i < dirs.count; i++)
		st_appendf(looked, sizeof(looked), "%s%s", i ? ", " : "", dirs.path[i]);
	return st_error_set(err, ST_ERR_ARG,
			    "no printer profile named '%.64s' (looked in %s and PrusaSlicer's "
			    "bundles); 'stratum printers' lists them",
			    name_or_path, looked);
}

/* qsort order of profile_list: by id. */
static int entry_cmp(const void *a, const void *b)
{
	return strcmp(((const struct profile_entry *)a)->id, ((const struct profile_entry *)b)->id);
}

void profile_list_free(struct profile_entry *list, size_t count)
{
	if (!list)
		return;
	for (size_t i = 0; i < count; i++) {
		free(list[i].id);
		free(list[i].path);
	}
	free(list);
}

int profile_list(struct profile_entry **out, size_t *count, struct st_error *err)
{
	struct profile_dirs dirs;
	struct profile_entry *list = NULL;
	size_t n = 0, cap = 0;

	if (!out || !count)
		return st_error_set(err, ST_ERR_ARG, "profile_list: bad arguments");
	*out = NULL;
	*count = 0;
	profile_search_dirs(&dirs);
	for (size_t d = 0; d < dirs.count; d++) {
		DIR *dir = opendir(dirs.path[d]);
		struct dirent *de;

		if (!dir)
			continue;
		while ((de = readdir(dir))) {
			size_t len = strlen(de->d_name);
			char path[PROFILE_PATH_MAX + 300];
			char *id;
			bool seen = false;

			if (len <= 4 || strcmp(de->d_name + len - 4, ".ini"))
				continue;
			id = prof_dup(de->d_name, len - 4);
			if (!id)
				goto out_nomem;
			for (size_t k = 0; k < n && !seen; k++)
				seen = !strcmp(list[k].id, id);
			snprintf(path, sizeof(path), "%s/%s", dirs.path[d], de->d_name);
			if (seen || !valid_name(id) || !is_regular_file(path)) {
				free(id);
				continue;
			}
			struct profile_entry *nl = st_grow(list, &cap, n + 1, sizeof(*nl));

			if (!nl) {
				free(id);
				closedir(dir);
				goto out_nomem;
			}
			list = nl;
			list[n].id = id;
			list[n].path = prof_dup(path, strlen(path));
			n++;
			if (!list[n - 1].path) {
				closedir(dir);
				goto out_nomem;
			}
		}
		closedir(dir);
	}
	if (n)
		qsort(list, n, sizeof(*list), entry_cmp);
	*out = list;
	*count = n;
	return 0;

out_nomem:
	profile_list_free(list, n);
	return st_error_set(err, ST_ERR_NOMEM, "out of memory listing printer profiles");
}

int profile_exit_status(int rc)
{
	return rc == ST_ERR_RANGE ? ST_EXIT_USAGE : st_exit_for(rc);
}
