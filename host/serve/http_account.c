/*
 * http_account.c - OctoPrint's calls about who is asking and what serves
 * them (docs/serve.md): the passive login farm managers open with, the
 * current user, the server's version, the system commands.  The node has
 * no users or passwords: the API key is the user, named by its [key NAME]
 * section, with OctoPrint's permissions for its roles.
 */
#include <jansson.h>
#include <microhttpd.h>
#include <string.h>

#include "http_int.h"


/* OctoPrint's permission names for a key's roles. */
static json_t *permissions(unsigned roles)
{
	static const struct {
		unsigned role;
		const char *name;
	} map[] = {
		{NODE_ROLE_READ, "STATUS"},	     {NODE_ROLE_READ, "CONNECTION"},
		{NODE_ROLE_READ, "FILES_LIST"},	     {NODE_ROLE_READ, "FILES_DOWNLOAD"},
		{NODE_ROLE_READ, "SETTINGS_READ"},   {NODE_ROLE_UPLOAD, "FILES_UPLOAD"},
		{NODE_ROLE_UPLOAD, "FILES_DELETE"},  {NODE_ROLE_UPLOAD, "FILES_SELECT"},
		{NODE_ROLE_CONTROL, "PRINT"},	     {NODE_ROLE_CONTROL, "CONTROL"},
	};
	json_t *arr = json_array();

	for (size_t i = 0; i < sizeof(map) / sizeof(map[0]); i++)
		if (roles & map[i].role)
			json_array_append_new(arr, json_string(map[i].name));
	return arr;
}

/* The key as OctoPrint's user record (login response); its session is
 * what the push API's auth message takes (push.c). */
static json_t *user_json(const struct node *n, const struct req *r)
{
	bool admin = (r->roles & NODE_ROLE_CONTROL) != 0;
	char session[NODE_PUSH_SESSION_LEN + 1] = "";

	for (size_t i = 0; i < n->cfg.nkeys; i++)
		if (!strcmp(n->cfg.keys[i].name, r->key_name))
			node_push_session(n->cfg.keys[i].secret, session);
	/* apikey stays null: the caller holds the key */
	return json_pack("{s:s,s:b,s:b,s:b,s:n,s:{},s:s,s:[s],s:o,s:o,s:b,s:s}", "name",
			 r->key_name, "active", 1, "admin", admin, "user", 1, "apikey", "settings",
			 "session", session, "groups", admin ? "admins" : "users", "permissions",
			 permissions(r->roles), "roles", json_pack("[s]", admin ? "admin" : "user"),
			 "_is_external_client", 0, "_login_mechanism", "apikey");
}

/* POST /api/login: {"passive": true} with a valid key gives its user; with
 * none, 204 as OctoPrint answers a passive login without a user.  There
 * are no passwords: an active login (user, pass) gets 403. */
enum MHD_Result http_post_login(struct node *n, struct MHD_Connection *c, struct req *r)
{
	enum MHD_Result ret;
	json_t *o = http_body_json(c, r, &ret);
	bool passive;

	if (!o)
		return ret;
	passive = json_object_get(o, "passive") != NULL;
	if (!passive && !json_object_get(o, "user")) {
		ret = http_send_error(c, MHD_HTTP_BAD_REQUEST, "Neither user and pass attributes nor "
							       "passive flag present");
	} else if (!passive) {
		ret = http_send_error(c, MHD_HTTP_FORBIDDEN, "the node has no user accounts: log in "
							     "passively with an API key");
	} else if (!r->key_name) {
		ret = http_no_content(c);
	} else {
		ret = http_send_json(c, MHD_HTTP_OK, user_json(n, r), NULL);
	}
	json_decref(o);
	return ret;
}

enum MHD_Result http_get_currentuser(struct node *n, struct MHD_Connection *c, struct req *r)
{
	bool admin = (r->roles & NODE_ROLE_CONTROL) != 0;

	(void)n;
	return http_send_json(c, MHD_HTTP_OK, json_pack("{s:s,s:o,s:[s]}", "name", r->key_name,
							"permissions", permissions(r->roles),
							"groups", admin ? "admins" : "users"), NULL);
}

enum MHD_Result http_get_server(struct node *n, struct MHD_Connection *c, struct req *r)
{
	(void)n;
	(void)r;
	return http_send_json(c, MHD_HTTP_OK, json_pack("{s:s,s:n}", "version",
							HTTP_OCTOPRINT_VERSION, "safemode"), NULL);
}

/* GET /api/system/commands[/core|/custom]: the node runs no system
 * commands (restart, shutdown ...), so every list is empty. */
enum MHD_Result http_get_system_commands(struct node *n, struct MHD_Connection *c, struct req *r)
{
	const char *source = r->rt->prefix ? http_tail(r) : NULL;

	(void)n;
	if (!source)
		return http_send_json(c, MHD_HTTP_OK, json_pack("{s:[],s:[]}", "core", "custom"),
				      NULL);
	if (strcmp(source, "core") && strcmp(source, "custom"))
		return http_send_error(c, MHD_HTTP_NOT_FOUND, "Unknown action source");
	return http_send_json(c, MHD_HTTP_OK, json_array(), NULL);
}
