/*
 * profile_vendor.c - printer names resolved through PrusaSlicer's installed
 * vendor bundles (profile.h, profile_find): "Original Prusa i3 MK3S &
 * MK3S+", or its slug original-prusa-i3-mk3s-mk3s, is the [printer:...]
 * preset of that name in the .ini files of PROFILE_VENDOR_DIR, loaded with its default
 * print and filament presets as `--load BUNDLE --printer-preset NAME` does.
 */
#include "profile_int.h"

#include <ctype.h>
#include <dirent.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>

/* The slug of s[0, len): lower-case letters and digits, each other run one '-'. */
static void slug(const char *s, size_t len, char *out, size_t cap)
{
	size_t o = 0;
	bool dash = false;

	for (size_t i = 0; i < len && o + 2 < cap; i++) {
		unsigned char c = (unsigned char)s[i];

		if (isalnum(c) && c < 0x80) {
			if (dash && o)
				out[o++] = '-';
			out[o++] = (char)tolower(c);
			dash = false;
		} else {
			dash = true;
		}
	}
	out[o] = '\0';
}

/* The [printer:NAME] of bundle path matching want (exact or by slug), copied. */
static char *find_preset(const char *path, const char *want, const char *want_slug)
{
	FILE *f = fopen(path, "r");
	char *line = NULL, *hit = NULL, s[256];
	size_t cap = 0;
	ssize_t n;

	if (!f)
		return NULL;
	while (!hit && (n = getline(&line, &cap, f)) > 0) {
		while (n > 0 && (line[n - 1] == '\n' || line[n - 1] == '\r' || line[n - 1] == ' '))
			line[--n] = '\0';
		if (n < 11 || strncmp(line, "[printer:", 9) || line[n - 1] != ']' || line[9] == '*')
			continue;
		size_t len = (size_t)n - 10;
		slug(line + 9, len, s, sizeof(s));
		if ((len == strlen(want) && !memcmp(line + 9, want, len)) ||
		    (*want_slug && !strcmp(s, want_slug)))
			hit = prof_dup(line + 9, len);
	}
	free(line);
	fclose(f);
	return hit;
}

int prof_find_vendor(const char *name, struct profile **out, struct st_error *err)
{
	const char *dir = getenv("STRATUM_VENDOR_DIR");
	char want_slug[256], path[PROFILE_PATH_MAX + 300];
	struct dirent **ents = NULL;
	int n, rc = 1;

	if (!dir || !*dir)
		dir = PROFILE_VENDOR_DIR;
	slug(name, strlen(name), want_slug, sizeof(want_slug));
	n = scandir(dir, &ents, NULL, alphasort);
	for (int i = 0; i < n; i++) {
		size_t len = strlen(ents[i]->d_name);
		char *preset;

		if (rc != 1 || len <= 4 || strcmp(ents[i]->d_name + len - 4, ".ini"))
			continue;
		snprintf(path, sizeof(path), "%s/%s", dir, ents[i]->d_name);
		if (!(preset = find_preset(path, name, want_slug)))
			continue;
		struct profile_layer layer = {.path = path};
		struct profile_presets pre = {.printer = preset};
		rc = profile_load_layers(NULL, &layer, 1, &pre, out, err);
		free(preset);
	}
	for (int i = 0; i < n; i++)
		free(ents[i]);
	free(ents);
	return rc;
}
