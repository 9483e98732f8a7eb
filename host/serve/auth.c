/*
 * auth.c - who may do what on the node (docs/serve.md "API", "MQTT"): the
 * API keys of the config, looked up for HTTP and MQTT alike; MQTT commands,
 * which carry a key with the control role or are signed with one
 * (HMAC-SHA256, libcrypto); and the hosts an MQTT enqueue may download from.
 */
#include <curl/curl.h>
#include <openssl/crypto.h>
#include <openssl/evp.h>
#include <openssl/hmac.h>
#include <ctype.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>
#include <strings.h>

#include "node_int.h"

unsigned node_key_roles(const struct node_config *cfg, const char *key, const char **who)
{
	unsigned roles = 0;
	size_t a = strlen(key);

	*who = NULL;
	/* Compare with every key in full so the time does not tell which matched. */
	for (size_t i = 0; i < cfg->nkeys; i++) {
		const char *s = cfg->keys[i].secret;
		size_t b = strlen(s);
		unsigned char diff = a != b;

		for (size_t k = 0; k < b; k++)
			diff |= (unsigned char)(s[k] ^ key[k < a ? k : 0]);
		if (!diff) {
			roles |= cfg->keys[i].roles;
			*who = cfg->keys[i].name;
		}
	}
	return roles;
}

/* The signed form: {"signed": TEXT, "by": KEY_NAME, "hmac": HEX}. */
static int check_signed(const struct node *n, const char *topic, json_t *env, json_t **cmd,
			const char **who, time_t now, struct st_error *err)
{
	const char *text = json_string_value(json_object_get(env, "signed"));
	const char *by = json_string_value(json_object_get(env, "by"));
	const char *hex = json_string_value(json_object_get(env, "hmac"));
	const struct node_key *key = NULL;
	unsigned char mac[EVP_MAX_MD_SIZE], given[32];
	unsigned int mac_len = 0;
	json_t *t;
	json_error_t je;

	*cmd = text ? json_loads(text, 0, &je) : NULL;
	if (!json_is_object(*cmd))
		return st_error_set(err, ST_ERR_PARSE, "signed: the signed text is not a JSON "
						       "object");
	if (!by || !hex || strlen(hex) != 64)
		return st_error_set(err, ST_ERR_ARG, "a signed command needs \"by\" (a key's name) "
						     "and \"hmac\" (64 hex digits)");
	for (int i = 0; i < 32; i++)
		if (sscanf(hex + 2 * i, "%2hhx", &given[i]) != 1)
			return st_error_set(err, ST_ERR_ARG, "hmac: not 64 hex digits");
	for (size_t i = 0; i < n->cfg.nkeys; i++)
		if (!strcmp(n->cfg.keys[i].name, by))
			key = &n->cfg.keys[i];
	/* HMAC over the topic too, so a command signed for one printer or node
	 * cannot be replayed to another. */
	if (key) {
		size_t tl = strlen(topic), xl = strlen(text);
		unsigned char *msg = malloc(tl + 1 + xl);

		if (!msg)
			return st_error_set(err, ST_ERR_NOMEM, "out of memory");
		memcpy(msg, topic, tl);
		msg[tl] = '\n';
		memcpy(msg + tl + 1, text, xl);
		HMAC(EVP_sha256(), key->secret, (int)strlen(key->secret), msg, tl + 1 + xl, mac,
		     &mac_len);
		free(msg);
	}
	if (!key || mac_len != 32 || CRYPTO_memcmp(mac, given, 32))
		return st_error_set(err, ST_ERR_RANGE, "the signature does not match a key of this "
						       "node (hmac of the topic, a newline and "
						       "the signed text)");
	if (!(key->roles & NODE_ROLE_CONTROL))
		return st_error_set(err, ST_ERR_RANGE, "the key lacks the control role");
	t = json_object_get(*cmd, "time");
	if (!json_is_integer(t))
		return st_error_set(err, ST_ERR_ARG, "a signed command needs \"time\" (Unix "
						     "seconds) so that it cannot be replayed later");
	if (json_integer_value(t) < (json_int_t)now - NODE_MQTT_SIGNED_WINDOW_S ||
	    json_integer_value(t) > (json_int_t)now + NODE_MQTT_SIGNED_WINDOW_S)
		return st_error_set(err, ST_ERR_RANGE, "time: %lld s from the node's clock; a signed "
						       "command is taken within %d s",
				    (long long)(json_integer_value(t) - (json_int_t)now),
				    NODE_MQTT_SIGNED_WINDOW_S);
	*who = key->name;
	return 0;
}

int node_mqtt_authorize(const struct node *n, const char *topic, const char *payload, time_t now,
			json_t **cmd, const char **who, struct st_error *err)
{
	json_error_t je;
	json_t *o = json_loads(payload, 0, &je);
	const char *key;
	unsigned roles;
	int rc;

	*cmd = NULL;
	*who = NULL;
	if (!json_is_object(o)) {
		json_decref(o);
		return st_error_set(err, ST_ERR_PARSE, "the command is not a JSON object");
	}
	if (json_object_get(o, "signed")) {
		rc = check_signed(n, topic, o, cmd, who, now, err);
		json_decref(o);
		return rc;
	}
	*cmd = o;
	key = json_string_value(json_object_get(o, "key"));
	if (!key)
		return st_error_set(err, ST_ERR_RANGE, "a key with the control role is needed "
						       "(\"key\", or the command signed with "
						       "one)");
	roles = node_key_roles(&n->cfg, key, who);
	if (!roles)
		return st_error_set(err, ST_ERR_RANGE, "the key is not a key of this node");
	if (!(roles & NODE_ROLE_CONTROL))
		return st_error_set(err, ST_ERR_RANGE, "the key lacks the control role");
	return 0;
}

/* Whether "host" or "host:port" of the allow list names host (lower case,
 * IPv6 in brackets) and port: a bare host allows the scheme's own port. */
static bool host_listed(const char *entry, const char *host, long port, long scheme_port)
{
	size_t hl = strlen(host);

	if (strncmp(entry, host, hl))
		return false;
	if (!entry[hl])
		return port == scheme_port;
	return entry[hl] == ':' && atol(entry + hl + 1) == port;
}

int node_mqtt_url_allowed(const struct node_mqtt_config *c, const char *url,
			  struct st_error *err)
{
	CURLU *u = curl_url();
	char *scheme = NULL, *host = NULL, *port = NULL;
	int rc = 0;

	if (!u)
		return st_error_set(err, ST_ERR_NOMEM, "out of memory");
	if (curl_url_set(u, CURLUPART_URL, url, 0) ||
	    curl_url_get(u, CURLUPART_SCHEME, &scheme, 0) ||
	    curl_url_get(u, CURLUPART_HOST, &host, 0) ||
	    curl_url_get(u, CURLUPART_PORT, &port, CURLU_DEFAULT_PORT)) {
		rc = st_error_set(err, ST_ERR_ARG, "'%.200s' is not a URL", url);
	} else if (strcmp(scheme, "http") && strcmp(scheme, "https")) {
		rc = st_error_set(err, ST_ERR_ARG, "url must be http:// or https://");
	} else {
		bool listed = false;

		for (char *s = host; *s; s++)
			*s = (char)tolower((unsigned char)*s);
		for (size_t i = 0; i < c->ndownload_hosts && !listed; i++)
			listed = host_listed(c->download_hosts[i], host, atol(port),
					     strcmp(scheme, "https") ? 80 : 443);
		if (!c->ndownload_hosts)
			rc = st_error_set(err, ST_ERR_RANGE, "downloads are off: [mqtt] "
							     "download_hosts lists no host");
		else if (!listed)
			rc = st_error_set(err, ST_ERR_RANGE, "%.100s:%s is not in [mqtt] "
							     "download_hosts", host, port);
	}
	curl_free(scheme);
	curl_free(host);
	curl_free(port);
	curl_url_cleanup(u);
	return rc;
}
