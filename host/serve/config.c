/*
 * config.c - the node's configuration (node.h node_config_load): [node],
 * [key NAME], [printer NAME] and [mqtt] sections of `key = value` lines,
 * read by the same ini reader as printer profiles (ini.h), so both take the
 * same line ends, BOM, blanks, comments and key syntax; here a ' #' or
 * ' ;' also starts a comment after a value.  Unknown sections and keys are errors so
 * a typo never silently leaves a printer unprotected.
 */
#include <arpa/inet.h>
#include <ctype.h>
#include <stddef.h>
#include <stdarg.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>
#include <sys/stat.h>

#include "ini.h"
#include "node.h"
#include "st_append.h"
#include "st_number.h"

enum section { SEC_NONE, SEC_NODE, SEC_KEY, SEC_PRINTER, SEC_MQTT, SEC_REMOTE };

/* Parse state: where we are, for messages and duplicate checks. */
struct cfg_parse {
	const char *file;
	int line;
	enum section sec;
	unsigned seen; /* bit per key of the current section */
	bool node_seen, mqtt_seen;
	struct node_config *cfg;
	struct farm_config *farm; /* a farm view's config (cfg is its base); NULL: a node's */
	bool keys_optional;	  /* no [key] section is fine (node_config_read) */
	struct st_error *err;
	char *scratch; /* the current line's key and value, NUL-terminated */
};

/* Error at the current line. */
#define CFG_FAIL(p, code, ...) cfg_fail((p), (code), __VA_ARGS__)
static int cfg_fail(struct cfg_parse *p, int code, const char *fmt, ...)
	__attribute__((format(printf, 3, 4)));
static int cfg_fail(struct cfg_parse *p, int code, const char *fmt, ...)
{
	char what[200];
	va_list ap;

	va_start(ap, fmt);
	vsnprintf(what, sizeof(what), fmt, ap);
	va_end(ap);
	return st_error_set(p->err, code, "%s: line %d: %s", p->file, p->line, what);
}

/* Trim blanks at both ends in place; returns the start. */
static char *trim(char *s)
{
	char *e;

	while (*s == ' ' || *s == '\t')
		s++;
	e = s + strlen(s);
	while (e > s && (e[-1] == ' ' || e[-1] == '\t' || e[-1] == '\r'))
		*--e = '\0';
	return s;
}

bool node_good_name(const char *s)
{
	size_t n = strlen(s);

	if (!n || n >= NODE_NAME_MAX || s[0] == '.')
		return false;
	for (; *s; s++)
		if (!isalnum((unsigned char)*s) && !strchr("-_.", *s))
			return false;
	return true;
}

/* Copy v into dst (cap bytes) or fail when it does not fit or is empty. */
static int copy_value(struct cfg_parse *p, const char *key, const char *v, char *dst, size_t cap)
{
	size_t n = strlen(v);

	if (!n)
		return CFG_FAIL(p, ST_ERR_RANGE, "%s: empty value", key);
	if (n >= cap)
		return CFG_FAIL(p, ST_ERR_RANGE, "%s: longer than %zu bytes", key, cap - 1);
	memcpy(dst, v, n + 1);
	return 0;
}

/* A whole number in [lo, hi].  The range is checked first: converting a
 * double beyond long long (99999999999999999999) is undefined behaviour. */
static int whole(struct cfg_parse *p, const char *key, const char *v, double lo, double hi,
		 double *out)
{
	double d;

	if (st_parse_double(v, strlen(v), 0, &d) != ST_NUMBER_OK)
		return CFG_FAIL(p, ST_ERR_PARSE, "%s: '%s' is not a whole number", key, v);
	if (!(d >= lo && d <= hi))
		return CFG_FAIL(p, ST_ERR_RANGE, "%s: %s is out of range (%g to %g)", key, v, lo,
				hi);
	if (d != floor(d))
		return CFG_FAIL(p, ST_ERR_PARSE, "%s: '%s' is not a whole number", key, v);
	*out = d;
	return 0;
}

int node_parse_roles(char *v, unsigned *roles, struct st_error *err)
{
	char *next = v, *tok;

	*roles = 0;
	while (next) {
		tok = next;
		next = strchr(tok, ',');
		if (next)
			*next++ = '\0';
		tok = trim(tok);
		if (!strcmp(tok, "read"))
			*roles |= NODE_ROLE_READ;
		else if (!strcmp(tok, "upload"))
			*roles |= NODE_ROLE_UPLOAD;
		else if (!strcmp(tok, "control"))
			*roles |= NODE_ROLE_CONTROL;
		else
			return st_error_set(err, ST_ERR_PARSE, "roles: '%.60s' is not a role (read, "
							       "upload, control)", tok);
	}
	if (!*roles)
		return st_error_set(err, ST_ERR_RANGE, "roles: give at least one of read, upload, "
						       "control");
	return 0;
}

/* roles = ... in a [key] section, with the file and line in the message. */
static int parse_roles(struct cfg_parse *p, char *v, unsigned *roles)
{
	struct st_error e;

	if (node_parse_roles(v, roles, &e))
		return CFG_FAIL(p, e.code, "%s", e.msg);
	return 0;
}

/* Mark key number bit of this section seen; fail on a duplicate. */
static int once(struct cfg_parse *p, const char *key, unsigned bit)
{
	if (p->seen & (1u << bit))
		return CFG_FAIL(p, ST_ERR_PARSE, "%s: set twice in this section", key);
	p->seen |= 1u << bit;
	return 0;
}

/* name = a section name (good_name). */
static int check_name(struct cfg_parse *p, char *v, void *base)
{
	(void)base;
	if (!node_good_name(v))
		return CFG_FAIL(p, ST_ERR_RANGE, "name: '%s' is not a name (letters, "
					       "digits, '-', '_', '.'; at most 63)", v);
	return 0;
}

static int set_listen(struct cfg_parse *p, char *v, void *base)
{
	struct node_config *c = base;
	struct st_error e;

	if (node_parse_listen(v, c->listen_addr, sizeof(c->listen_addr), &c->listen_port, &e))
		return CFG_FAIL(p, e.code, "listen: %s", e.msg);
	return 0;
}

/* An API key: NODE_KEY_MIN to NODE_KEY_MAX printable bytes, into secret. */
static int copy_secret(struct cfg_parse *p, const char *v, char secret[NODE_KEY_MAX + 1])
{
	size_t n = strlen(v);

	if (n < NODE_KEY_MIN || n > NODE_KEY_MAX)
		return CFG_FAIL(p, ST_ERR_RANGE, "key: %zu bytes; an API key has %d to %d", n,
				NODE_KEY_MIN, NODE_KEY_MAX);
	for (const char *s = v; *s; s++)
		if (!isgraph((unsigned char)*s))
			return CFG_FAIL(p, ST_ERR_RANGE, "key: only printable characters "
							"without blanks");
	memcpy(secret, v, n + 1);
	return 0;
}

static int set_secret(struct cfg_parse *p, char *v, void *base)
{
	return copy_secret(p, v, ((struct node_key *)base)->secret);
}

static int set_node_key(struct cfg_parse *p, char *v, void *base)
{
	(void)base;
	return copy_secret(p, v, p->farm->node_key);
}

static int set_remote_key(struct cfg_parse *p, char *v, void *base)
{
	return copy_secret(p, v, ((struct farm_remote *)base)->key);
}

static int set_roles(struct cfg_parse *p, char *v, void *base)
{
	return parse_roles(p, v, &((struct node_key *)base)->roles);
}

static int check_prefix(struct cfg_parse *p, char *v, void *base)
{
	size_t n = strlen(v);

	(void)base;
	if (n < 2 || v[0] != '/' || v[n - 1] == '/' || strstr(v, "//") || strstr(v, "/.") ||
	    !strncmp(v, "/api", 4) ||
	    strspn(v, "/abcdefghijklmnopqrstuvwxyzABCDEFGHIJKLMNOPQRSTUVWXYZ0123456789-_.") != n)
		return CFG_FAIL(p, ST_ERR_RANGE, "prefix: '%s' is not a URL path such as "
						 "/p/mk3s (starts with '/', no trailing "
						 "'/', not under /api)", v);
	return 0;
}

/* url = http(s)://HOST[:PORT][/PATH], no trailing '/', nothing to quote. */
static int check_url(struct cfg_parse *p, char *v, void *base)
{
	size_t n = strlen(v);
	size_t scheme = !strncmp(v, "http://", 7) ? 7 : !strncmp(v, "https://", 8) ? 8 : 0;

	(void)base;
	if (!scheme || n == scheme || v[n - 1] == '/' ||
	    strspn(v, "abcdefghijklmnopqrstuvwxyzABCDEFGHIJKLMNOPQRSTUVWXYZ0123456789-._~:/[]%") != n)
		return CFG_FAIL(p, ST_ERR_RANGE, "url: '%s' is not a URL such as "
						 "http://farm-1.lan:5000 (http or https, no "
						 "trailing '/')", v);
	return 0;
}

static int check_tls_version(struct cfg_parse *p, char *v, void *base)
{
	(void)base;
	if (strcmp(v, "tlsv1.2") && strcmp(v, "tlsv1.3"))
		return CFG_FAIL(p, ST_ERR_RANGE, "tls_version: '%s' is not tlsv1.2 or tlsv1.3", v);
	return 0;
}

/* download_hosts = HOST[:PORT], ...: names, IPv4 or [IPv6] addresses. */
static int set_download_hosts(struct cfg_parse *p, char *v, void *base)
{
	struct node_mqtt_config *m = base;
	char *next = v, *tok;

	m->ndownload_hosts = 0;
	while (next) {
		const char *host_end, *port;
		double d = 0;

		tok = next;
		next = strchr(tok, ',');
		if (next)
			*next++ = '\0';
		tok = trim(tok);
		for (char *s = tok; *s; s++)
			*s = (char)tolower((unsigned char)*s);
		host_end = tok[0] == '[' ? strchr(tok, ']') : tok + strcspn(tok, ":");
		if (host_end && tok[0] == '[')
			host_end++;
		port = host_end && *host_end == ':' ? host_end + 1 : NULL;
		if (!host_end || host_end == tok || (*host_end && !port) ||
		    strspn(tok, tok[0] == '[' ? "[]:0123456789abcdef." :
			   "abcdefghijklmnopqrstuvwxyz0123456789.-") < (size_t)(host_end - tok) ||
		    (port && (st_parse_double(port, strlen(port), 0, &d) != ST_NUMBER_OK ||
			      !(d >= 1 && d <= 65535) || d != floor(d) || strchr(port, '.'))))
			return CFG_FAIL(p, ST_ERR_RANGE, "download_hosts: '%s' is not HOST or "
							 "HOST:PORT (a name or address, port 1 to "
							 "65535)", tok);
		if (m->ndownload_hosts == NODE_MQTT_HOSTS_MAX)
			return CFG_FAIL(p, ST_ERR_RANGE, "download_hosts: more than %d hosts",
					NODE_MQTT_HOSTS_MAX);
		if (strlen(tok) >= sizeof(m->download_hosts[0]))
			return CFG_FAIL(p, ST_ERR_RANGE, "download_hosts: '%.40s...' is too long", tok);
		snprintf(m->download_hosts[m->ndownload_hosts++], sizeof(m->download_hosts[0]), "%s",
			 tok);
	}
	return 0;
}

static int check_topic(struct cfg_parse *p, char *v, void *base)
{
	(void)base;
	if (strpbrk(v, "+#") || v[0] == '/' || (*v && v[strlen(v) - 1] == '/'))
		return CFG_FAIL(p, ST_ERR_RANGE, "topic: '%s' is not a topic root such as "
						 "stratum (no + or #, no leading or "
						 "trailing /)", v);
	return 0;
}

/*
 * One key of a section, declared once: the parser, the duplicate check
 * (a key's bit is its place in the table) and the list of a section's keys
 * in the message for an unknown one all read it.  After check (if any), a
 * text key is copied to the field at off, a whole number in lo..hi is
 * stored as the field's type, and a KEY_SET key's check does all.
 */
enum key_kind { KEY_TEXT, KEY_INT, KEY_UNSIGNED, KEY_U16, KEY_DOUBLE, KEY_MB, KEY_SET };
struct cfg_key {
	const char *name;
	enum key_kind kind;
	size_t off, size; /* the field in the section's struct */
	double lo, hi;
	int (*check)(struct cfg_parse *p, char *v, void *base);
};
#define TEXT(s, f, chk) {#f, KEY_TEXT, offsetof(s, f), sizeof(((s *)0)->f), 0, 0, chk}
#define WHOLE(s, f, kind, lo, hi) {#f, kind, offsetof(s, f), 0, lo, hi, NULL}

/* [node] is entries 1 to the end; a farm's [farm] is 0 to FARM_KEYS - 1:
 * node_key and the keys that set up the HTTP server, declared once for both. */
static const struct cfg_key node_keys[] = {
    {"node_key", KEY_SET, 0, 0, 0, 0, set_node_key},
    TEXT(struct node_config, name, check_name),
    {"listen", KEY_SET, 0, 0, 0, 0, set_listen},
    {"max_upload_mb", KEY_MB, offsetof(struct node_config, max_upload), 0, 1, 1 << 20, NULL},
    WHOLE(struct node_config, max_connections, KEY_UNSIGNED, NODE_CONN_MIN, NODE_CONN_MAX),
    WHOLE(struct node_config, max_connections_per_ip, KEY_UNSIGNED, 1, NODE_CONN_MAX),
    WHOLE(struct node_config, idle_timeout_s, KEY_UNSIGNED, 1, 3600),
    WHOLE(struct node_config, header_timeout_s, KEY_UNSIGNED, 1, 3600),
    WHOLE(struct node_config, min_body_rate, KEY_UNSIGNED, 0, 1 << 30),
    TEXT(struct node_config, url, check_url),
    TEXT(struct node_config, data_dir, NULL),
    WHOLE(struct node_config, slice_threads, KEY_INT, 0, 256),
};
#define FARM_KEYS 9
static const struct cfg_key remote_keys[] = {
    {"key", KEY_SET, 0, 0, 0, 0, set_remote_key},
    TEXT(struct farm_remote, url, check_url),
};
static const struct cfg_key key_keys[] = {
    {"key", KEY_SET, 0, 0, 0, 0, set_secret},
    {"roles", KEY_SET, 0, 0, 0, 0, set_roles},
};
static const struct cfg_key printer_keys[] = {
    TEXT(struct node_printer_config, profile, NULL),
    TEXT(struct node_printer_config, port, NULL),
    TEXT(struct node_printer_config, prefix, check_prefix),
    WHOLE(struct node_printer_config, sim_speedup, KEY_DOUBLE, 1, 100000),
};
static const struct cfg_key mqtt_keys[] = {
    TEXT(struct node_mqtt_config, host, NULL),
    WHOLE(struct node_mqtt_config, port, KEY_U16, 1, 65535),
    TEXT(struct node_mqtt_config, username, NULL),
    TEXT(struct node_mqtt_config, password, NULL),
    TEXT(struct node_mqtt_config, topic, check_topic),
    WHOLE(struct node_mqtt_config, keepalive, KEY_INT, 5, 3600),
    WHOLE(struct node_mqtt_config, tls, KEY_INT, 0, 1),
    TEXT(struct node_mqtt_config, ca_file, NULL),
    TEXT(struct node_mqtt_config, ca_dir, NULL),
    TEXT(struct node_mqtt_config, cert_file, NULL),
    TEXT(struct node_mqtt_config, key_file, NULL),
    TEXT(struct node_mqtt_config, tls_version, check_tls_version),
    WHOLE(struct node_mqtt_config, tls_insecure, KEY_INT, 0, 1),
    {"download_hosts", KEY_SET, 0, 0, 0, 0, set_download_hosts},
};
#define KEYS(t) t, sizeof(t) / sizeof(t[0])

/* k = v in the section whose keys are keys[n] and whose struct is base;
 * section names it in the message for an unknown key ("[node]"). */
static int set_key(struct cfg_parse *p, const struct cfg_key *keys, size_t n, void *base,
		   const char *section, const char *k, char *v)
{
	char list[200] = "";

	for (size_t i = 0; i < n; i++) {
		const struct cfg_key *d = &keys[i];
		void *field = (char *)base + d->off;
		double x = 0;
		int rc;

		if (strcmp(k, d->name))
			continue;
		if ((rc = once(p, k, (unsigned)i)) || (d->check && (rc = d->check(p, v, base))))
			return rc;
		if (d->kind == KEY_TEXT)
			return copy_value(p, k, v, field, d->size);
		if (d->kind != KEY_SET && (rc = whole(p, k, v, d->lo, d->hi, &x)))
			return rc;
		if (d->kind == KEY_INT)
			*(int *)field = (int)x;
		else if (d->kind == KEY_UNSIGNED)
			*(unsigned *)field = (unsigned)x;
		else if (d->kind == KEY_U16)
			*(uint16_t *)field = (uint16_t)x;
		else if (d->kind == KEY_DOUBLE)
			*(double *)field = x;
		else if (d->kind == KEY_MB)
			*(uint64_t *)field = (uint64_t)x << 20;
		return 0;
	}
	for (size_t i = 0; i < n; i++)
		st_appendf(list, sizeof(list), "%s%s", i ? ", " : "", keys[i].name);
	return CFG_FAIL(p, ST_ERR_PARSE, "unknown key '%s' in %s (%s)", k, section, list);
}

/* "[node]", "[key NAME]", "[printer NAME]" or "[mqtt]"; in a farm view's
 * config "[farm]", "[key NAME]", "[remote NODE]" or "[mqtt]". */
static int section_line(struct cfg_parse *p, char *s)
{
	struct node_config *c = p->cfg;
	const char *main_sec = p->farm ? "farm" : "node", *named = p->farm ? "remote" : "printer";
	const char *list = p->farm ? "farm, key NAME, remote NODE, mqtt"
				   : "node, key NAME, printer NAME, mqtt";
	char *end = strchr(s, ']'), *name;

	if (!end || trim(end + 1)[0])
		return CFG_FAIL(p, ST_ERR_PARSE, "a section line is one of [%s]", list);
	*end = '\0';
	s = trim(s + 1);
	p->seen = 0;
	if (!strcmp(s, main_sec)) {
		if (p->node_seen)
			return CFG_FAIL(p, ST_ERR_PARSE, "[%s] given twice", main_sec);
		p->node_seen = true;
		p->sec = SEC_NODE;
		return 0;
	}
	if (!strcmp(s, "mqtt")) {
		if (p->mqtt_seen)
			return CFG_FAIL(p, ST_ERR_PARSE, "[mqtt] given twice");
		p->mqtt_seen = true;
		p->sec = SEC_MQTT;
		return 0;
	}
	name = strchr(s, ' ');
	if (!name)
		return CFG_FAIL(p, ST_ERR_PARSE, "unknown section [%s] (%s)", s, list);
	*name = '\0';
	name = trim(name + 1);
	if (!node_good_name(name))
		return CFG_FAIL(p, ST_ERR_RANGE, "'%s' is not a name (letters, digits, '-', '_', "
						 "'.'; at most 63)", name);
	if (!strcmp(s, "key")) {
		if (c->nkeys == NODE_MAX_KEYS)
			return CFG_FAIL(p, ST_ERR_RANGE, "more than %d keys", NODE_MAX_KEYS);
		for (size_t i = 0; i < c->nkeys; i++)
			if (!strcmp(c->keys[i].name, name))
				return CFG_FAIL(p, ST_ERR_PARSE, "[key %s] given twice", name);
		snprintf(c->keys[c->nkeys++].name, NODE_NAME_MAX, "%s", name);
		p->sec = SEC_KEY;
		return 0;
	}
	if (strcmp(s, named))
		return CFG_FAIL(p, ST_ERR_PARSE, "unknown section [%s %s] (%s)", s, name, list);
	if (p->farm) {
		struct farm_config *f = p->farm;

		if (f->nremotes == FARM_MAX_REMOTES)
			return CFG_FAIL(p, ST_ERR_RANGE, "more than %d remotes", FARM_MAX_REMOTES);
		for (size_t i = 0; i < f->nremotes; i++)
			if (!strcmp(f->remotes[i].name, name))
				return CFG_FAIL(p, ST_ERR_PARSE, "[remote %s] given twice", name);
		snprintf(f->remotes[f->nremotes++].name, NODE_NAME_MAX, "%s", name);
		p->sec = SEC_REMOTE;
		return 0;
	}
	if (c->nprinters == NODE_MAX_PRINTERS)
		return CFG_FAIL(p, ST_ERR_RANGE, "more than %d printers", NODE_MAX_PRINTERS);
	for (size_t i = 0; i < c->nprinters; i++)
		if (!strcmp(c->printers[i].name, name))
			return CFG_FAIL(p, ST_ERR_PARSE, "[printer %s] given twice", name);
	snprintf(c->printers[c->nprinters].name, NODE_NAME_MAX, "%s", name);
	c->printers[c->nprinters++].sim_speedup = 100;
	p->sec = SEC_PRINTER;
	return 0;
}

/* A section line from the ini reader: copied so it can be cut up. */
static int on_section(void *ctx, int line, const char *text, size_t len, struct st_error *err)
{
	struct cfg_parse *p = ctx;

	(void)err; /* p->err is the same */
	p->line = line;
	memcpy(p->scratch, text, len);
	p->scratch[len] = '\0';
	return section_line(p, p->scratch);
}

/* A key = value line from the ini reader, into the current section. */
static int on_entry(void *ctx, const struct ini_entry *e, struct st_error *err)
{
	struct cfg_parse *p = ctx;
	char *k = p->scratch, *v = p->scratch + e->key_len + 1, sec[NODE_NAME_MAX + 16];

	(void)err;
	p->line = e->line;
	memcpy(k, e->key, e->key_len);
	k[e->key_len] = '\0';
	memcpy(v, e->value, e->value_len);
	v[e->value_len] = '\0';
	switch (p->sec) {
	case SEC_NODE:
		if (p->farm)
			return set_key(p, node_keys, FARM_KEYS, p->cfg, "[farm]", k, v);
		return set_key(p, node_keys + 1, sizeof(node_keys) / sizeof(node_keys[0]) - 1,
			       p->cfg, "[node]", k, v);
	case SEC_REMOTE:
		snprintf(sec, sizeof(sec), "[remote %s]", p->farm->remotes[p->farm->nremotes - 1].name);
		return set_key(p, KEYS(remote_keys), &p->farm->remotes[p->farm->nremotes - 1], sec,
			       k, v);
	case SEC_KEY:
		snprintf(sec, sizeof(sec), "[key %s]", p->cfg->keys[p->cfg->nkeys - 1].name);
		return set_key(p, KEYS(key_keys), &p->cfg->keys[p->cfg->nkeys - 1], sec, k, v);
	case SEC_PRINTER:
		snprintf(sec, sizeof(sec), "[printer %s]",
			 p->cfg->printers[p->cfg->nprinters - 1].name);
		return set_key(p, KEYS(printer_keys), &p->cfg->printers[p->cfg->nprinters - 1], sec,
			       k, v);
	case SEC_MQTT:
		return set_key(p, KEYS(mqtt_keys), &p->cfg->mqtt, "[mqtt]", k, v);
	default:
		return CFG_FAIL(p, ST_ERR_PARSE, "'%s' before any [section]", k);
	}
}

/* [mqtt] as a whole: the broker, TLS keys only with tls = 1, the defaults
 * that follow from other keys. */
static int check_mqtt(struct cfg_parse *p)
{
	struct node_mqtt_config *m = &p->cfg->mqtt;
	const char *tls_key = m->ca_file[0]	 ? "ca_file"
			      : m->ca_dir[0]	 ? "ca_dir"
			      : m->cert_file[0]	 ? "cert_file"
			      : m->key_file[0]	 ? "key_file"
			      : m->tls_version[0] ? "tls_version"
			      : m->tls_insecure	 ? "tls_insecure"
						 : NULL;

	if (p->mqtt_seen && !m->host[0])
		return st_error_set(p->err, ST_ERR_RANGE, "%s: [mqtt] needs host =", p->file);
	if (tls_key && !m->tls)
		return st_error_set(p->err, ST_ERR_RANGE, "%s: [mqtt] %s is a TLS setting: add "
							  "tls = 1 (without it the link is not "
							  "encrypted)", p->file, tls_key);
	if (!m->cert_file[0] != !m->key_file[0])
		return st_error_set(p->err, ST_ERR_RANGE, "%s: [mqtt] cert_file and key_file go "
							  "together (the client certificate and its "
							  "key)", p->file);
	if (m->cert_file[0] && !m->ca_file[0] && !m->ca_dir[0])
		return st_error_set(p->err, ST_ERR_RANGE, "%s: [mqtt] a client certificate needs "
							  "ca_file or ca_dir (the broker's CA)",
				    p->file);
	if (m->password[0] && !m->username[0])
		return st_error_set(p->err, ST_ERR_RANGE, "%s: [mqtt] password needs username",
				    p->file);
	if (!m->port)
		m->port = m->tls ? NODE_MQTT_TLS_PORT : NODE_MQTT_PORT;
	if (!m->topic[0])
		snprintf(m->topic, sizeof(m->topic), "stratum");
	/* One client id per node name: a second node of that name is refused
	 * before it connects with it (mqtt_name.c), never knocks the first off. */
	snprintf(m->client_id, sizeof(m->client_id), "stratum-%s%s", p->farm ? "farm-" : "",
		 p->cfg->name);
	return 0;
}

/* What every section must have, checked once the whole file is read;
 * p->keys_optional lets a file without [key] through (--new-key). */
static int check_complete(struct cfg_parse *p)
{
	struct node_config *c = p->cfg;

	p->line = 0;
	if (!c->nkeys && !p->keys_optional)
		return st_error_set(p->err, ST_ERR_RANGE, "%s: no [key NAME] section: the %s "
							  "refuses every request without a key",
				    p->file, p->farm ? "farm view" : "node");
	for (size_t i = 0; i < c->nkeys; i++)
		if (!c->keys[i].secret[0] || !c->keys[i].roles)
			return st_error_set(p->err, ST_ERR_RANGE, "%s: [key %s] needs key = and "
								  "roles =", p->file, c->keys[i].name);
	for (size_t i = 0; p->farm && i < p->farm->nremotes; i++)
		if (!p->farm->remotes[i].key[0])
			return st_error_set(p->err, ST_ERR_RANGE, "%s: [remote %s] needs key =",
					    p->file, p->farm->remotes[i].name);
	if (!c->nprinters && !p->farm)
		return st_error_set(p->err, ST_ERR_RANGE, "%s: no [printer NAME] section", p->file);
	for (size_t i = 0; i < c->nprinters; i++) {
		struct node_printer_config *pc = &c->printers[i];

		if (!pc->profile[0] || !pc->port[0])
			return st_error_set(p->err, ST_ERR_RANGE, "%s: [printer %s] needs profile = "
								  "and port =", p->file, pc->name);
		if (!pc->prefix[0])
			snprintf(pc->prefix, sizeof(pc->prefix), "/p/%s", pc->name);
		for (size_t j = 0; j < i; j++)
			if (!strcmp(c->printers[j].prefix, pc->prefix))
				return st_error_set(p->err, ST_ERR_RANGE, "%s: printers %s and %s "
									  "have the same prefix %s",
						    p->file, c->printers[j].name, pc->name,
						    pc->prefix);
	}
	return check_mqtt(p);
}

/* A path key (field, cap NODE_PATH_MAX) relative to the config file's folder. */
static int resolve_path(const char *path, const char *key, char *field, struct st_error *err)
{
	char full[NODE_PATH_MAX];
	const char *slash = strrchr(path, '/');

	if (!field[0] || field[0] == '/' || !slash)
		return 0;
	if (snprintf(full, sizeof(full), "%.*s/%s", (int)(slash - path), path, field) >=
	    (int)sizeof(full))
		return st_error_set(err, ST_ERR_RANGE, "%s: %s: path too long", path, key);
	memcpy(field, full, sizeof(full));
	return 0;
}

/* data_dir and the TLS files relative to the config file's folder. */
static int resolve_paths(struct node_config *c, bool farm, const char *path, struct st_error *err)
{
	struct node_mqtt_config *m = &c->mqtt;
	int rc;

	if (!c->data_dir[0] && !farm)
		return st_error_set(err, ST_ERR_RANGE, "%s: [node] needs data_dir = (where the "
						       "queue and the files are kept)", path);
	if ((rc = resolve_path(path, "data_dir", c->data_dir, err)) ||
	    (rc = resolve_path(path, "ca_file", m->ca_file, err)) ||
	    (rc = resolve_path(path, "ca_dir", m->ca_dir, err)) ||
	    (rc = resolve_path(path, "cert_file", m->cert_file, err)))
		return rc;
	return resolve_path(path, "key_file", m->key_file, err);
}

/* Read a node's config into *c, or with farm a farm view's (c its base);
 * keys_optional lets a node's config without [key] through (--new-key). */
static int config_load(const char *path, struct node_config *c, struct farm_config *farm,
		       bool keys_optional, struct st_error *err)
{
	static const struct ini_handler handler = {on_section, on_entry, true, false};
	struct cfg_parse p = {.file = path, .cfg = c, .farm = farm, .keys_optional = keys_optional,
			      .err = err};
	char *text = NULL;
	size_t len;
	int rc;

	/* a line's key and value, each at most a line long, plus their NULs */
	p.scratch = malloc(2 * INI_LINE_MAX + 2);
	if (!p.scratch) {
		rc = st_error_set(err, ST_ERR_NOMEM, "%s: out of memory", path);
		goto out_free;
	}
	rc = ini_read_file(path, &text, &len, err);
	if (rc)
		goto out_free;
	snprintf(c->path, sizeof(c->path), "%s", path);
	snprintf(c->name, sizeof(c->name), "stratum");
	snprintf(c->listen_addr, sizeof(c->listen_addr), "127.0.0.1");
	c->listen_port = 5000;
	c->mqtt.keepalive = 30;
	c->max_upload = NODE_UPLOAD_DEFAULT;
	c->slice_threads = 1;
	c->max_connections = NODE_CONN_DEFAULT;
	c->max_connections_per_ip = NODE_CONN_PER_IP_DEFAULT;
	c->idle_timeout_s = NODE_IDLE_TIMEOUT_DEFAULT;
	c->header_timeout_s = NODE_HEADER_TIMEOUT_DEFAULT;
	c->min_body_rate = NODE_MIN_BODY_RATE_DEFAULT;
	if (!(rc = ini_parse(text, len, path, &handler, &p, err)) && !(rc = check_complete(&p)))
		rc = resolve_paths(c, farm != NULL, path, err);
out_free:
	free(text);
	free(p.scratch);
	return rc;
}

int node_config_read(const char *path, struct node_config *out, bool keys_required,
		     struct st_error *err)
{
	struct node_config *c = calloc(1, sizeof(*c));
	int rc;

	if (!c)
		return st_error_set(err, ST_ERR_NOMEM, "%s: out of memory", path);
	if (!(rc = config_load(path, c, NULL, !keys_required, err)))
		*out = *c;
	free(c);
	return rc;
}

int node_config_load(const char *path, struct node_config *out, struct st_error *err)
{
	return node_config_read(path, out, true, err);
}

int farm_config_load(const char *path, struct farm_config *out, struct st_error *err)
{
	struct farm_config *f = calloc(1, sizeof(*f));
	int rc;

	if (!f)
		return st_error_set(err, ST_ERR_NOMEM, "%s: out of memory", path);
	if (!(rc = config_load(path, &f->base, f, false, err)))
		*out = *f;
	free(f);
	return rc;
}

bool node_config_exposed(const char *path, const struct node_config *cfg, unsigned *mode)
{
	struct stat st;

	if ((!cfg->nkeys && !cfg->mqtt.password[0]) || stat(path, &st) != 0)
		return false;
	*mode = (unsigned)st.st_mode & 07777u;
	return (st.st_mode & 077) != 0;
}

int node_parse_listen(const char *s, char *addr, size_t cap, uint16_t *port,
		      struct st_error *err)
{
	const char *colon = strrchr(s, ':');
	struct in_addr in;
	char host[INET_ADDRSTRLEN];
	double d;

	if (!colon || colon == s || (size_t)(colon - s) >= sizeof(host))
		goto out_bad;
	memcpy(host, s, (size_t)(colon - s));
	host[colon - s] = '\0';
	if (inet_pton(AF_INET, host, &in) != 1 ||
	    st_parse_double(colon + 1, strlen(colon + 1), 0, &d) != ST_NUMBER_OK ||
	    strchr(colon + 1, '.'))
		goto out_bad;
	/* Range before the whole-number test: (long)d is undefined beyond long. */
	if (!(d >= 0 && d <= 65535))
		return st_error_set(err, ST_ERR_RANGE, "'%s': port %s is out of range (0 to "
						       "65535)", s, colon + 1);
	if (d != floor(d))
		goto out_bad;
	if (!inet_ntop(AF_INET, &in, addr, (socklen_t)cap))
		goto out_bad;
	*port = (uint16_t)d;
	return 0;

out_bad:
	return st_error_set(err, ST_ERR_PARSE, "'%s' is not ADDRESS:PORT such as 127.0.0.1:5000 "
					       "(IPv4, port 0 to 65535)", s);
}
