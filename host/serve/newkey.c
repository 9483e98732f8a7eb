/*
 * newkey.c - `stratum serve --new-key NAME --roles ROLES` (node.h
 * node_config_new_key): an API key made by the node in OctoPrint's form (16
 * random bytes as 32 upper-case hex digits), added to the config as a
 * [key NAME] section.  The keys live in the config (docs/serve.md,
 * "Config"), so the file is rewritten whole: a reader (the node starting,
 * another --new-key) sees the old file or the new one, never half of it.
 */
#include <fcntl.h>
#include <limits.h>
#include <openssl/rand.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>
#include <sys/file.h>
#include <unistd.h>

#include "ini.h"
#include "node.h"
#include "st_file.h"

/* The config holds every key: readable and writable by its owner only. */
#define NEW_KEY_FILE_MODE 0600

static int make_key(char key[NODE_NEW_KEY_LEN + 1], struct st_error *err)
{
	unsigned char raw[NODE_NEW_KEY_LEN / 2];

	if (RAND_bytes(raw, (int)sizeof(raw)) != 1)
		return st_error_set(err, ST_ERR_INTERNAL, "no random bytes for the key (OpenSSL's "
							  "generator failed)");
	for (size_t i = 0; i < sizeof(raw); i++)
		snprintf(key + 2 * i, 3, "%02X", raw[i]);
	return 0;
}

/* The roles bits as the config writes them. */
static void roles_text(unsigned roles, char *out, size_t cap)
{
	snprintf(out, cap, "%s%s%s%s%s", roles & NODE_ROLE_READ ? "read" : "",
		 (roles & NODE_ROLE_READ) && (roles & ~NODE_ROLE_READ) ? ", " : "",
		 roles & NODE_ROLE_UPLOAD ? "upload" : "",
		 (roles & NODE_ROLE_UPLOAD) && (roles & NODE_ROLE_CONTROL) ? ", " : "",
		 roles & NODE_ROLE_CONTROL ? "control" : "");
}

/* Write text and the new section to the file of o, check that it loads with
 * the key, then put it in path's place. */
static int write_config(struct st_file_out *o, const char *path, const char *text, size_t len,
			const char *section, struct st_error *err)
{
	struct node_config *check = malloc(sizeof(*check));
	struct st_error e;
	int rc;

	if (!check) {
		st_file_abort(o);
		return st_error_set(err, ST_ERR_NOMEM, "%s: out of memory", path);
	}
	errno = 0;
	if (fchmod(fileno(o->f), NEW_KEY_FILE_MODE) != 0 || fwrite(text, 1, len, o->f) != len ||
	    (len && text[len - 1] != '\n' && fputc('\n', o->f) == EOF) ||
	    fputs(section, o->f) == EOF) {
		free(check);
		return st_file_fail(o, err);
	}
	if ((rc = st_file_finish(o, err))) {
		free(check);
		return rc;
	}
	if (node_config_read(o->tmp, check, true, &e)) {
		free(check);
		st_file_abort(o);
		return st_error_set(err, ST_ERR_INTERNAL, "%s: the config with the new key does not "
							  "load (%s); the file was left unchanged",
				    path, e.msg);
	}
	free(check);
	return st_file_publish(o, path, err);
}

int node_config_new_key(const char *path, const char *name, const char *roles,
			char key[NODE_NEW_KEY_LEN + 1], struct st_error *err)
{
	char roles_copy[256], roles_norm[32], real[PATH_MAX], section[NODE_NAME_MAX + 128];
	struct node_config *cfg = NULL;
	struct st_file_out o;
	unsigned bits;
	char *text = NULL, *slash;
	size_t len;
	int rc, dir_fd = -1;

	if (!node_good_name(name))
		return st_error_set(err, ST_ERR_ARG, "--new-key: '%.80s' is not a key name (letters, "
						     "digits, '-', '_', '.'; at most 63)", name);
	snprintf(roles_copy, sizeof(roles_copy), "%s", roles);
	if (strlen(roles) >= sizeof(roles_copy) || node_parse_roles(roles_copy, &bits, err))
		return st_error_set(err, ST_ERR_ARG, "--roles: '%.80s' is not a list of roles "
						     "(read, upload, control, comma separated)",
				    roles);
	/* The file itself, not a symbolic link to it, is replaced. */
	if (!realpath(path, real))
		return st_error_set(err, ST_ERR_IO, "%s: cannot open: %s", path, strerror(errno));
	/* One --new-key at a time per folder: each rewrites the whole file. */
	slash = strrchr(real, '/');
	*slash = '\0';
	dir_fd = open(slash == real ? "/" : real, O_RDONLY | O_DIRECTORY);
	*slash = '/';
	if (dir_fd >= 0 && flock(dir_fd, LOCK_EX) != 0) {
		close(dir_fd);
		dir_fd = -1;
	}
	if (!(cfg = malloc(sizeof(*cfg)))) {
		rc = st_error_set(err, ST_ERR_NOMEM, "%s: out of memory", path);
		goto out;
	}
	if ((rc = node_config_read(real, cfg, false, err)))
		goto out;
	for (size_t i = 0; i < cfg->nkeys; i++)
		if (!strcmp(cfg->keys[i].name, name)) {
			rc = st_error_set(err, ST_ERR_RANGE, "%s: [key %s] exists already; give "
							     "another name, or delete that section "
							     "to replace its key", path, name);
			goto out;
		}
	if (cfg->nkeys == NODE_MAX_KEYS) {
		rc = st_error_set(err, ST_ERR_RANGE, "%s: the config has %d keys, the most a node "
						     "takes", path, NODE_MAX_KEYS);
		goto out;
	}
	if ((rc = make_key(key, err)) || (rc = ini_read_file(real, &text, &len, err)))
		goto out;
	roles_text(bits, roles_norm, sizeof(roles_norm));
	snprintf(section, sizeof(section), "\n[key %s]\nkey = %s\nroles = %s\n", name, key,
		 roles_norm);
	if (!(rc = st_file_begin(&o, real, err)))
		rc = write_config(&o, real, text, len, section, err);
out:
	if (rc)
		memset(key, 0, NODE_NEW_KEY_LEN + 1);
	free(text);
	free(cfg);
	if (dir_fd >= 0)
		close(dir_fd); /* and the lock with it */
	return rc;
}
