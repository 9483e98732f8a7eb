/*
 * http_files.c - OctoPrint's file calls on a printer's stored files
 * (docs/serve.md): the list (GET /api/files[/local], ?recursive=true), one
 * file or folder, the select/move/copy commands, deletion, and the download
 * every entry links to.  Paths are checked part by part as upload paths are
 * (http_check_rel), so no call reaches outside the printer's files.
 */
#include <dirent.h>
#include <errno.h>
#include <fcntl.h>
#include <ftw.h>
#include <jansson.h>
#include <microhttpd.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>
#include <strings.h>
#include <sys/stat.h>
#include <sys/statvfs.h>
#include <unistd.h>

#include "http_int.h"

#define FILES_DEPTH_MAX 16 /* folder levels listed or deleted */

/* rel checked and its full path in full; false for a path that is no file
 * name of ours (answered as missing: it cannot exist). */
static bool full_path(const struct node_printer *p, const char *rel, char *full, size_t cap)
{
	struct st_error err;

	if (!rel[0] || rel[0] == '/' || rel[strlen(rel) - 1] == '/' ||
	    http_check_rel(rel, strlen(rel), &err))
		return false;
	return snprintf(full, cap, "%s/%s", p->files_dir, rel) < (int)cap;
}

void http_files_changed(struct node_printer *p)
{
	atomic_fetch_add(&p->files_version, 1);
}

/* Whether the query parameter name is OctoPrint's true. */
static bool query_true(struct MHD_Connection *c, const char *name)
{
	const char *v = MHD_lookup_connection_value(c, MHD_GET_ARGUMENT_KIND, name);

	return v && (!strcasecmp(v, "true") || !strcmp(v, "1") || !strcasecmp(v, "yes"));
}

/* scandir's filter: the names the node would store (others are left out). */
static int storable(const struct dirent *d)
{
	struct st_error err;

	return !node_check_file_name(d->d_name, strlen(d->d_name), &err);
}

static int by_name(const struct dirent **a, const struct dirent **b)
{
	return strcmp((*a)->d_name, (*b)->d_name);
}

static json_t *entry_json(struct MHD_Connection *c, struct req *r, const char *rel,
			  const struct stat *st, bool recursive, int depth, int64_t *size);

/* The entries of folder rel ("" the top) into arr, sorted by name; their
 * bytes added to *size.  Names the node would not store are left out. */
static void list_folder(struct MHD_Connection *c, struct req *r, const char *rel, bool recursive,
			int depth, json_t *arr, int64_t *size)
{
	char dir[2 * NODE_PATH_MAX], child[NODE_PATH_MAX + NODE_FILE_NAME_MAX + 2];
	struct dirent **names = NULL;
	int n;

	snprintf(dir, sizeof(dir), "%s%s%s", r->p->files_dir, rel[0] ? "/" : "", rel);
	n = scandir(dir, &names, storable, by_name); /* -1: none */
	for (int i = 0; i < n; i++) {
		const char *name = names[i]->d_name;
		char full[sizeof(dir) + NODE_FILE_NAME_MAX + 2];
		struct stat st;
		json_t *e;

		snprintf(child, sizeof(child), "%s%s%s", rel, rel[0] ? "/" : "", name);
		snprintf(full, sizeof(full), "%s/%s", dir, name);
		if (!stat(full, &st) && (S_ISDIR(st.st_mode) || node_file_kind(name)) &&
		    (e = entry_json(c, r, child, &st, recursive, depth + 1, size)))
			json_array_append_new(arr, e);
		free(names[i]);
	}
	free(names);
}

/* A file's or folder's entry; a folder's children when recursive (or at
 * the first level asked for, depth 0). */
static json_t *entry_json(struct MHD_Connection *c, struct req *r, const char *rel,
			  const struct stat *st, bool recursive, int depth, int64_t *size)
{
	char res[2048];
	const char *slash = strrchr(rel, '/');
	json_t *o, *children;
	int64_t inner = 0;

	if (!S_ISDIR(st->st_mode)) {
		struct node_gcode_estimate est;
		char full[2 * NODE_PATH_MAX];

		*size += st->st_size;
		o = http_file_json(c, r, rel, st);
		json_object_set_new(o, "display", json_string(slash ? slash + 1 : rel));
		snprintf(full, sizeof(full), "%s/%s", r->p->files_dir, rel);
		node_gcode_summary(full, &est);
		if (est.time_s >= 0 || est.filament_mm >= 0)
			json_object_set_new(o, "gcodeAnalysis", json_pack(
				"{s:o,s:{s:{s:o,s:o}}}", "estimatedPrintTime",
				est.time_s >= 0 ? json_integer((json_int_t)est.time_s) : json_null(),
				"filament", "tool0", "length", est.filament_mm >= 0
				? json_real(est.filament_mm) : json_null(), "volume",
				est.filament_cm3 >= 0 ? json_real(est.filament_cm3) : json_null()));
		return o;
	}
	http_url_for(c, r, "/api/files/local/", rel, res, sizeof(res));
	o = json_pack("{s:s,s:s,s:s,s:s,s:s,s:[s],s:{s:s}}", "name", slash ? slash + 1 : rel,
		      "display", slash ? slash + 1 : rel, "path", rel, "origin", "local", "type",
		      "folder", "typePath", "folder", "refs", "resource", res);
	if ((recursive || depth == 0) && depth < FILES_DEPTH_MAX) {
		children = json_array();
		list_folder(c, r, rel, recursive, depth, children, &inner);
		json_object_set_new(o, "children", children);
		json_object_set_new(o, "size", json_integer(inner));
		*size += inner;
	}
	return o;
}

/* GET /api/files and /api/files/local: the top folder (every level with
 * ?recursive=true), and the space of the files' file system. */
enum MHD_Result http_get_files(struct node *n, struct MHD_Connection *c, struct req *r)
{
	json_t *files = json_array(), *o;
	struct statvfs vfs;
	int64_t size = 0;

	(void)n;
	list_folder(c, r, "", query_true(c, "recursive"), 0, files, &size);
	o = json_pack("{s:o}", "files", files);
	if (!statvfs(r->p->files_dir, &vfs)) {
		json_object_set_new(o, "free", json_integer((json_int_t)(vfs.f_bavail * vfs.f_frsize)));
		json_object_set_new(o, "total", json_integer((json_int_t)(vfs.f_blocks * vfs.f_frsize)));
	}
	return http_send_json(c, MHD_HTTP_OK, o, NULL);
}

/* GET /api/files/local/PATH: a file's entry, or a folder's with its children. */
enum MHD_Result http_get_file(struct node *n, struct MHD_Connection *c, struct req *r)
{
	const char *rel = http_tail(r);
	char full[2 * NODE_PATH_MAX];
	int64_t size = 0;
	struct stat st;

	(void)n;
	if (!full_path(r->p, rel, full, sizeof(full)) || stat(full, &st) ||
	    !(S_ISREG(st.st_mode) || S_ISDIR(st.st_mode)))
		return http_send_error(c, MHD_HTTP_NOT_FOUND, "File not found");
	return http_send_json(c, MHD_HTTP_OK,
			      entry_json(c, r, rel, &st, query_true(c, "recursive"), 0, &size), NULL);
}

/* Whether a queued or running job of p uses a file under full (the file,
 * or any file of the folder). */
static bool in_use(struct node *n, struct node_printer *p, const char *full, int depth)
{
	struct dirent *d;
	struct stat st;
	bool busy = false;
	DIR *dh;

	if (stat(full, &st))
		return false;
	if (!S_ISDIR(st.st_mode))
		return node_queue_file_busy(n->q, p->cfg->name, full) != 0;
	if (depth > FILES_DEPTH_MAX || !(dh = opendir(full)))
		return true; /* when in doubt, keep it */
	while (!busy && (d = readdir(dh))) {
		char child[2 * NODE_PATH_MAX + NODE_FILE_NAME_MAX];

		if (strcmp(d->d_name, ".") && strcmp(d->d_name, "..") &&
		    snprintf(child, sizeof(child), "%s/%s", full, d->d_name) < (int)sizeof(child))
			busy = in_use(n, p, child, depth + 1);
	}
	closedir(dh);
	return busy;
}

/* nftw's step of removing a tree: each entry after its contents. */
static int remove_entry(const char *path, const struct stat *st, int type, struct FTW *ftw)
{
	(void)st;
	(void)type;
	(void)ftw;
	return remove(path);
}

/* The selected file is rel or under the folder rel. */
static bool selected_under(struct node *n, const struct node_printer *p, const char *rel)
{
	char sel[NODE_PATH_MAX];
	size_t len = strlen(rel);

	node_queue_selected(n->q, p->cfg->name, sel, sizeof(sel));
	return sel[0] && !strncmp(sel, rel, len) && (!sel[len] || sel[len] == '/');
}

/* DELETE /api/files/local/PATH: 204; 404; 409 while a job (queued,
 * printing, paused) uses the file or a file of the folder. */
enum MHD_Result http_delete_file(struct node *n, struct MHD_Connection *c, struct req *r)
{
	struct node_printer *p = r->p;
	const char *rel = http_tail(r);
	char full[2 * NODE_PATH_MAX];
	struct st_error err = {0};
	enum MHD_Result ret;
	struct stat st;

	if (!full_path(p, rel, full, sizeof(full)) || stat(full, &st))
		return http_send_error(c, MHD_HTTP_NOT_FOUND, "File not found");
	pthread_mutex_lock(&p->mu); /* no job is queued meanwhile */
	if (in_use(n, p, full, 0)) {
		ret = http_send_error(c, MHD_HTTP_CONFLICT, "Trying to delete a file that is "
					 "currently in use: a job of the queue prints it");
	} else if (nftw(full, remove_entry, 16, FTW_DEPTH | FTW_PHYS)) {
		node_log("error", p->cfg->name, 0, "%s: cannot delete: %s", full, strerror(errno));
		ret = http_send_error(c, MHD_HTTP_INTERNAL_SERVER_ERROR, "cannot delete the file");
	} else {
		if (selected_under(n, p, rel) && node_queue_set_selected(n->q, p->cfg->name, "", &err))
			node_log("error", p->cfg->name, 0, "%s", err.msg);
		node_log("info", p->cfg->name, 0, "deleted %s", rel);
		http_files_changed(p);
		ret = http_no_content(c);
	}
	pthread_mutex_unlock(&p->mu);
	return ret;
}

/* GET /downloads/files/local/PATH: the file's bytes. */
enum MHD_Result http_download_file(struct node *n, struct MHD_Connection *c, struct req *r)
{
	const char *rel = http_tail(r), *slash = strrchr(rel, '/');
	char full[2 * NODE_PATH_MAX], disp[NODE_FILE_NAME_MAX + 40];
	struct MHD_Response *resp;
	enum MHD_Result ret;
	struct stat st;
	int fd;

	(void)n;
	if (!full_path(r->p, rel, full, sizeof(full)) || (fd = open(full, O_RDONLY)) < 0)
		return http_send_error(c, MHD_HTTP_NOT_FOUND, "File not found");
	if (fstat(fd, &st) || !S_ISREG(st.st_mode) ||
	    !(resp = MHD_create_response_from_fd((uint64_t)st.st_size, fd))) {
		close(fd);
		return http_send_error(c, MHD_HTTP_NOT_FOUND, "File not found");
	}
	/* The name is one of ours (no control byte: node_check_file_name); a
	 * quote would end the header's string. */
	snprintf(disp, sizeof(disp), "attachment; filename=\"%s\"", slash ? slash + 1 : rel);
	for (char *q = disp + 22; (q = strchr(q, '"')) && q[1]; q++)
		*q = '_';
	MHD_add_response_header(resp, MHD_HTTP_HEADER_CONTENT_TYPE, "application/octet-stream");
	MHD_add_response_header(resp, MHD_HTTP_HEADER_CONTENT_DISPOSITION, disp);
	ret = MHD_queue_response(c, MHD_HTTP_OK, resp);
	MHD_destroy_response(resp);
	return ret;
}

/* "select": make rel the selected file and, with print, queue it (a print
 * needs the control role). */
static enum MHD_Result file_select(struct node *n, struct MHD_Connection *c, struct req *r,
				   const char *rel, bool print)
{
	struct node_printer *p = r->p;
	struct st_error err = {0};
	struct node_job j;
	enum MHD_Result ret;

	if (print && !(r->roles & NODE_ROLE_CONTROL))
		return http_send_error(c, MHD_HTTP_FORBIDDEN, "the API key lacks the role this call "
							      "needs (print=true: control)");
	pthread_mutex_lock(&p->mu);
	if (p->job_id || node_queue_active(n->q, p->cfg->name, &j, NULL) == 1)
		ret = http_send_error(c, MHD_HTTP_CONFLICT, "Printer is already printing, cannot "
							    "select a new file");
	else if (print && !p->connected)
		ret = http_send_error(c, MHD_HTTP_CONFLICT, "Printer is not operational, cannot "
							    "directly start printing");
	else if (node_queue_set_selected(n->q, p->cfg->name, rel, &err))
		ret = http_send_error(c, MHD_HTTP_INTERNAL_SERVER_ERROR, err.msg);
	else
		ret = print ? http_start_selected(n, c, p) : http_no_content(c);
	pthread_mutex_unlock(&p->mu);
	return ret;
}

/* Copy the file src to dst through a temporary file (st_file.h); 0 or -1. */
static int copy_file(struct node *n, const char *src, const char *dst)
{
	struct st_file_out out = {0};
	char buf[65536];
	size_t got;
	FILE *in = fopen(src, "rb");
	int rc = -1;

	if (!in)
		return -1;
	if (!st_file_begin_temp(&out, n->tmp_dir, "copy", NULL)) {
		while ((got = fread(buf, 1, sizeof(buf), in)) > 0)
			if (fwrite(buf, 1, got, out.f) != got)
				break;
		if (!ferror(in) && !ferror(out.f) && !st_file_finish(&out, NULL) &&
		    !st_file_publish(&out, dst, NULL))
			rc = 0;
		st_file_abort(&out);
	}
	fclose(in);
	return rc;
}

/* "move" and "copy" of the file rel to destination: a folder it goes into
 * (keeping its name) or a new path.  201 with the new entry's refs. */
static enum MHD_Result file_move(struct node *n, struct MHD_Connection *c, struct req *r,
				 const char *rel, const char *full, const char *dest, bool move)
{
	struct node_printer *p = r->p;
	const char *name = strrchr(rel, '/');
	char to[NODE_PATH_MAX + NODE_FILE_NAME_MAX + 2], tofull[2 * NODE_PATH_MAX + 2];
	char res[2048], dl[2048], msg[400];
	struct st_error err = {0};
	enum MHD_Result ret;
	struct stat st;
	json_t *o;

	name = name ? name + 1 : rel;
	while (*dest == '/')
		dest++;
	/* "" or an existing folder: into it, under the same name */
	snprintf(tofull, sizeof(tofull), "%s/%s", p->files_dir, dest);
	if (!dest[0] || (!stat(tofull, &st) && S_ISDIR(st.st_mode)))
		snprintf(to, sizeof(to), "%s%s%s", dest, dest[0] && dest[strlen(dest) - 1] != '/'
			 ? "/" : "", name);
	else
		snprintf(to, sizeof(to), "%s", dest);
	if (!full_path(p, to, tofull, sizeof(tofull))) {
		snprintf(msg, sizeof(msg), "bad destination: %.300s (each part a file name the "
			 "node stores)", to);
		return http_send_error(c, MHD_HTTP_BAD_REQUEST, msg);
	}
	if (node_file_kind(to) != node_file_kind(rel))
		return http_send_error(c, MHD_HTTP_BAD_REQUEST, "the destination's extension must be "
							        "of the same kind as the file's");
	{
		char parent[sizeof(tofull)];
		char *slash;

		snprintf(parent, sizeof(parent), "%s", tofull);
		slash = strrchr(parent, '/');
		*slash = '\0';
		if (stat(parent, &st) || !S_ISDIR(st.st_mode))
			return http_send_error(c, MHD_HTTP_CONFLICT, "the destination folder does not "
								     "exist");
	}
	pthread_mutex_lock(&p->mu);
	if (!stat(tofull, &st)) {
		ret = http_send_error(c, MHD_HTTP_CONFLICT, "File or folder does already exist");
	} else if (move && (in_use(n, p, full, 0) || p->job_id)) {
		ret = http_send_error(c, MHD_HTTP_CONFLICT, "Trying to move a file that is currently "
							    "in use: a job of the queue prints it");
	} else if (move ? link(full, tofull) || unlink(full) : copy_file(n, full, tofull)) {
		/* link, not rename: a file stored there meanwhile is not replaced */
		node_log("error", p->cfg->name, 0, "%s: cannot %s to %s: %s", full, move ? "move"
			 : "copy", tofull, strerror(errno));
		ret = http_send_error(c, MHD_HTTP_INTERNAL_SERVER_ERROR, move ? "cannot move the file"
								       : "cannot copy the file");
	} else {
		if (move && selected_under(n, p, rel) &&
		    node_queue_set_selected(n->q, p->cfg->name, to, &err))
			node_log("error", p->cfg->name, 0, "%s", err.msg);
		node_log("info", p->cfg->name, 0, "%s %s to %s", move ? "moved" : "copied", rel, to);
		http_files_changed(p);
		http_url_for(c, r, "/api/files/local/", to, res, sizeof(res));
		http_url_for(c, r, "/downloads/files/local/", to, dl, sizeof(dl));
		o = json_pack("{s:s,s:s,s:s,s:{s:s,s:s}}", "name", strrchr(to, '/') ?
			      strrchr(to, '/') + 1 : to, "path", to, "origin", "local", "refs",
			      "resource", res, "download", dl);
		ret = http_send_json(c, MHD_HTTP_CREATED, o, res);
	}
	pthread_mutex_unlock(&p->mu);
	return ret;
}

/* POST /api/files/local/PATH: {"command": "select", "print": bool},
 * {"command": "move"|"copy", "destination": PATH}. */
enum MHD_Result http_post_file(struct node *n, struct MHD_Connection *c, struct req *r)
{
	const char *rel = http_tail(r), *cmd, *dest;
	char full[2 * NODE_PATH_MAX];
	enum MHD_Result ret;
	struct stat st;
	json_t *o;

	if (!full_path(r->p, rel, full, sizeof(full)) || stat(full, &st) || !S_ISREG(st.st_mode))
		return http_send_error(c, MHD_HTTP_NOT_FOUND, "File not found");
	if (!(o = http_body_json(c, r, &ret)))
		return ret;
	cmd = json_string_value(json_object_get(o, "command"));
	dest = json_string_value(json_object_get(o, "destination"));
	if (cmd && !strcmp(cmd, "select"))
		ret = file_select(n, c, r, rel, json_is_true(json_object_get(o, "print")));
	else if (cmd && (!strcmp(cmd, "move") || !strcmp(cmd, "copy")) && dest)
		ret = file_move(n, c, r, rel, full, dest, !strcmp(cmd, "move"));
	else if (cmd && !strcmp(cmd, "slice"))
		ret = http_send_error(c, MHD_HTTP_BAD_REQUEST, "the node slices a model when it is "
							       "queued (upload or select with print=true)");
	else
		ret = http_send_error(c, MHD_HTTP_BAD_REQUEST, "command is select, move or copy "
							       "(move and copy with destination)");
	json_decref(o);
	return ret;
}

enum MHD_Result http_make_folder(struct node *n, struct MHD_Connection *c, struct req *r)
{
	struct node_printer *p = r->p;
	const char *folder = r->path;
	char rel[HTTP_FIELD_MAX + NODE_FILE_NAME_MAX + 2], full[2 * NODE_PATH_MAX], res[2048];
	char msg[400];
	struct st_error err = {0};
	struct stat st;

	(void)n;
	while (*folder == '/')
		folder++;
	if (node_check_file_name(r->foldername, r->foldername_len, &err) ||
	    strlen(folder) != r->path_len - (size_t)(folder - r->path) ||
	    http_check_rel(folder, strlen(folder), &err)) {
		snprintf(msg, sizeof(msg), "bad folder name or path: %s", err.msg[0] ? err.msg
											 : "NUL byte");
		return http_send_error(c, MHD_HTTP_BAD_REQUEST, msg);
	}
	snprintf(rel, sizeof(rel), "%s%s%s", folder, *folder && folder[strlen(folder) - 1] != '/'
							 ? "/" : "", r->foldername);
	if (!full_path(p, rel, full, sizeof(full)))
		return http_send_error(c, MHD_HTTP_BAD_REQUEST, "the folder's path is too long");
	snprintf(res, sizeof(res), "%s", full);
	*strrchr(res, '/') = '\0';
	if (stat(res, &st) || !S_ISDIR(st.st_mode))
		return http_send_error(c, MHD_HTTP_CONFLICT, "the parent folder does not exist");
	if (mkdir(full, 0750))
		return http_send_error(c, errno == EEXIST ? MHD_HTTP_CONFLICT
				       : MHD_HTTP_INTERNAL_SERVER_ERROR, errno == EEXIST
				       ? "File or folder does already exist" : "cannot create the folder");
	node_log("info", p->cfg->name, 0, "created folder %s", rel);
	http_files_changed(p);
	http_url_for(c, r, "/api/files/local/", rel, res, sizeof(res));
	return http_send_json(c, MHD_HTTP_CREATED,
			      json_pack("{s:{s:s,s:s,s:s,s:{s:s}},s:b}", "folder", "name",
					r->foldername, "path", rel, "origin", "local", "refs",
					"resource", res, "done", 1), res);
}
