/*
 * check_servemqtt.c - the farm node on an MQTT broker that others share
 * (docs/serve.md "MQTT"), part of the serve suite: commands run only with a
 * key with the control role or signed with one (a second node of one name
 * is refused: check_servemqtt_name.c), the broker's credentials and TLS, downloads only from the
 * configured hosts (redirects too), and the broker examples of the docs
 * loaded by mosquitto.  Each test runs its own mosquitto on loopback.
 */
#include <check.h>
#include <pthread.h>
#include <signal.h>
#include <openssl/evp.h>
#include <openssl/hmac.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>
#include <sys/stat.h>
#include <time.h>
#include <unistd.h>

#include "mqtttest.h"
#include "serve/node.h"
#include "servetest.h"
#include "suites.h"
#include "testutil.h"

/* The [mqtt] keys that would leave a link open or a setting ignored are
 * refused when the config is read, with the key named. */
START_TEST(test_mqtt_config_errors)
{
	static const struct {
		const char *lines, *want;
	} cases[] = {
		{"ca_file = ca.pem\n", "[mqtt] ca_file is a TLS setting: add tls = 1"},
		{"tls_insecure = 1\n", "[mqtt] tls_insecure is a TLS setting"},
		{"tls = 1\ncert_file = c.pem\n", "cert_file and key_file go together"},
		{"tls = 1\ncert_file = c.pem\nkey_file = k.pem\n", "a client certificate needs "
								   "ca_file or ca_dir"},
		{"tls = 1\ntls_version = tlsv1.1\n", "line 12: tls_version: 'tlsv1.1' is not tlsv1.2 "
						     "or tlsv1.3"},
		{"tls = 2\n", "line 11: tls: 2 is out of range (0 to 1)"},
		{"password = p\n", "[mqtt] password needs username"},
		{"download_hosts = files.farm, http://x\n", "line 11: download_hosts: 'http://x' is "
							    "not HOST or HOST:PORT"},
		{"download_hosts = h:0\n", "'h:0' is not HOST or HOST:PORT"},
		{"download_hosts = [::1]:99999\n", "'[::1]:99999' is not HOST or HOST:PORT"},
		{"client_id = x\n", "line 11: unknown key 'client_id' in [mqtt]"},
	};
	struct node_config *c = calloc(1, sizeof(*c));
	struct st_error err = {0};
	const char *path = tu_path("mqtt-config.ini");
	char text[1024];

	ck_assert_ptr_nonnull(c);
	for (size_t i = 0; i < sizeof(cases) / sizeof(cases[0]); i++) {
		snprintf(text, sizeof(text), "[node]\ndata_dir = d\n[key k]\nkey = " KEY_CTL "\n"
					     "roles = control\n" ONE_PRINTER "[mqtt]\nhost = b\n%s",
			 cases[i].lines);
		tu_write_str(path, text);
		ck_assert_msg(node_config_load(path, c, &err) != 0, "%s loads", cases[i].lines);
		ck_assert_msg(strstr(err.msg, cases[i].want), "%s: %s", cases[i].lines, err.msg);
	}
	/* What loads: hosts lower-cased, ports by scheme, the client id from the name. */
	snprintf(text, sizeof(text), "[node]\nname = farm-7\ndata_dir = d\n[key k]\nkey = " KEY_CTL
				     "\nroles = control\n" ONE_PRINTER "[mqtt]\nhost = b\ntls = 1\n"
				     "ca_dir = certs\ndownload_hosts = Files.Farm, [::1]:8080\n");
	tu_write_str(path, text);
	ck_assert_msg(node_config_load(path, c, &err) == 0, "%s", err.msg);
	ck_assert_uint_eq(c->mqtt.port, 8883);
	ck_assert_str_eq(c->mqtt.client_id, "stratum-farm-7");
	ck_assert_str_eq(c->mqtt.download_hosts[0], "files.farm");
	ck_assert_str_eq(c->mqtt.download_hosts[1], "[::1]:8080");
	ck_assert_msg(strstr(c->mqtt.ca_dir, "/certs") && c->mqtt.ca_dir[0] == '/', "%s",
		      c->mqtt.ca_dir);
	free(c);
}
END_TEST

/* The signed form of the command text for topic, signed with secret as
 * key name by. */
static void sign(char *out, size_t cap, const char *topic, const char *text, const char *by,
		 const char *secret)
{
	unsigned char mac[32];
	unsigned int len = 0;
	char msg[1024], hex[65];
	json_t *env;
	char *dump;

	snprintf(msg, sizeof(msg), "%s\n%s", topic, text);
	HMAC(EVP_sha256(), secret, (int)strlen(secret), (const unsigned char *)msg, strlen(msg), mac,
	     &len);
	ck_assert_uint_eq(len, 32);
	for (int i = 0; i < 32; i++)
		snprintf(hex + 2 * i, 3, "%02x", mac[i]);
	env = json_pack("{s:s,s:s,s:s}", "signed", text, "by", by, "hmac", hex);
	dump = json_dumps(env, JSON_COMPACT);
	snprintf(out, cap, "%s", dump);
	free(dump);
	json_decref(env);
}

/* Commands without a key, with a wrong one, with one lacking the control
 * role, signed wrongly, late or for another topic are refused (and use up
 * no id); a control key or a good signature runs them.  No key is logged. */
START_TEST(test_mqtt_command_keys)
{
	struct node_proc np;
	struct mqtt_seen seen;
	struct mosquitto *mq;
	char out[2048], cmd[1024], text[512];
	int bport;
	pid_t broker;
	long long id;
	size_t len;
	char *log;

	if (!have_broker("MQTT command keys"))
		return;
	broker = node_on_broker(&np, &bport, "", &seen, &mq);
	id = sv_print_text(np.port, "", "hold.gcode", "G28\nG4 P20000\nG1 X5\n");
	sv_wait_state(np.port, "", id, "printing", 10);

	mqtt_command(mq, &seen, "{\"id\":\"k-1\",\"command\":\"pause\"}", "\"k-1\"", out,
		     sizeof(out));
	ck_assert_msg(strstr(out, "\"ok\":false") && strstr(out, "a key with the control role is "
								 "needed"),
		      "%s", out);
	mqtt_command(mq, &seen,
		     "{\"id\":\"k-2\",\"command\":\"pause\",\"key\":\"wrong-key-0123456789\"}",
		     "\"k-2\"", out, sizeof(out));
	ck_assert_msg(strstr(out, "the key is not a key of this node"), "%s", out);
	ck_assert_msg(!strstr(out, "wrong-key"), "the answer holds the key: %s", out);
	mqtt_command(mq, &seen, "{\"id\":\"k-3\",\"command\":\"pause\",\"key\":\"" KEY_UP "\"}",
		     "\"k-3\"", out, sizeof(out));
	ck_assert_msg(strstr(out, "the key lacks the control role"), "%s", out);
	mqtt_command(mq, &seen, "{\"id\":\"k-4\",\"command\":\"pause\",\"key\":\"" KEY_READ "\"}",
		     "\"k-4\"", out, sizeof(out));
	ck_assert_msg(strstr(out, "the key lacks the control role"), "%s", out);
	/* Signed: with the wrong secret, too late, for another printer's topic. */
	snprintf(text, sizeof(text), "{\"id\":\"k-5\",\"command\":\"pause\",\"time\":%lld}",
		 (long long)time(NULL));
	sign(cmd, sizeof(cmd), CMD_TOPIC, text, "operator", "not-the-operator-key-01");
	mqtt_command(mq, &seen, cmd, "\"k-5\"", out, sizeof(out));
	ck_assert_msg(strstr(out, "the signature does not match a key of this node"), "%s", out);
	snprintf(text, sizeof(text), "{\"id\":\"k-6\",\"command\":\"pause\",\"time\":%lld}",
		 (long long)time(NULL) - 1000);
	sign(cmd, sizeof(cmd), CMD_TOPIC, text, "operator", KEY_CTL);
	mqtt_command(mq, &seen, cmd, "\"k-6\"", out, sizeof(out));
	ck_assert_msg(strstr(out, "a signed command is taken within 300 s"), "%s", out);
	snprintf(text, sizeof(text), "{\"id\":\"k-7\",\"command\":\"pause\",\"time\":%lld}",
		 (long long)time(NULL));
	sign(cmd, sizeof(cmd), "stratum/test-node/ender/cmd", text, "operator", KEY_CTL);
	mqtt_command(mq, &seen, cmd, "\"k-7\"", out, sizeof(out));
	ck_assert_msg(strstr(out, "the signature does not match"), "%s", out);
	snprintf(text, sizeof(text), "{\"id\":\"k-8\",\"command\":\"pause\",\"time\":%lld}",
		 (long long)time(NULL));
	sign(cmd, sizeof(cmd), CMD_TOPIC, text, "slicer", KEY_UP);
	mqtt_command(mq, &seen, cmd, "\"k-8\"", out, sizeof(out));
	ck_assert_msg(strstr(out, "the key lacks the control role"), "%s", out);
	ck_assert_str_eq(sv_job_state(np.port, "", id, NULL), "printing");

	/* The control key: k-1 runs now, its refusal used up nothing. */
	mqtt_command(mq, &seen, "{\"id\":\"k-1\",\"command\":\"pause\",\"key\":\"" KEY_CTL "\"}",
		     "\"ok\":true", out, sizeof(out));
	ck_assert_msg(strstr(out, "\"k-1\"") && strstr(out, "\"duplicate\":false"), "%s", out);
	sv_wait_state(np.port, "", id, "paused", 10);
	/* Signed with the control key; the same message again is a duplicate. */
	snprintf(text, sizeof(text), "{\"id\":\"k-9\",\"command\":\"resume\",\"time\":%lld}",
		 (long long)time(NULL));
	sign(cmd, sizeof(cmd), CMD_TOPIC, text, "operator", KEY_CTL);
	mqtt_command(mq, &seen, cmd, "\"k-9\"", out, sizeof(out));
	ck_assert_msg(strstr(out, "\"ok\":true"), "%s", out);
	sv_wait_state(np.port, "", id, "printing", 10);
	mqtt_command(mq, &seen, cmd, "\"duplicate\":true", out, sizeof(out));
	mqtt_command(mq, &seen, "{\"id\":\"k-10\",\"command\":\"cancel\",\"key\":\"" KEY_CTL "\"}",
		     "\"k-10\"", out, sizeof(out));
	sv_wait_state(np.port, "", id, "cancelled", 10);

	watch_stop(mq, &seen);
	sv_stop(&np);
	log = tu_slurp(np.log, &len);
	ck_assert_msg(strstr(log, "mqtt: command pause (id k-2) refused: the key is not a key of "
				  "this node"), "%s", log);
	ck_assert_msg(!strstr(log, "wrong-key") && !strstr(log, KEY_UP) && !strstr(log, KEY_CTL) &&
			      !strstr(log, KEY_READ),
		      "a key is in the log: %s", log);
	free(log);
	broker_stop(broker);
}
END_TEST

/* A broker that requires a user name and password: the right ones connect;
 * a wrong password refuses the start (65) without printing it, and the
 * config holding it is named when others can read it. */
START_TEST(test_mqtt_password)
{
	struct node_proc np;
	struct mqtt_seen seen;
	struct mosquitto *mq;
	char out[4096], conf[1024], passwd[512];
	int bport, rc;
	pid_t broker;
	size_t len;
	char *log;

	if (!have_broker("MQTT password"))
		return;
	if (access("/usr/bin/mosquitto_passwd", X_OK)) {
		printf("serve: MQTT password test skipped: no /usr/bin/mosquitto_passwd\n");
		return;
	}
	bport = free_port();
	snprintf(passwd, sizeof(passwd), "%s", tu_path("broker.passwd"));
	rc = tu_sh(out, sizeof(out), "mosquitto_passwd -c -b '%s' test-node node-pass-123 && "
				     "mosquitto_passwd -b '%s' watcher watch-pass-123", passwd, passwd);
	ck_assert_msg(rc == 0, "%s", out);
	snprintf(conf, sizeof(conf), "listener %d 127.0.0.1\nallow_anonymous false\n"
				     "password_file %s\npersistence false\n", bport, passwd);
	broker = broker_start(bport, conf);
	mq = watch_start(&seen, bport, "watcher", "watch-pass-123", "stratum/test-node/#");

	write_mqtt_config(&np, bport, "username = test-node\npassword = not-the-pass-99\n");
	chmod(np.config, 0644);
	rc = tu_run(out, sizeof(out), "serve --config '%s'", np.config);
	ck_assert_msg(rc == 65, "exit %d: %s", rc, out);
	ck_assert_msg(strstr(out, "mqtt: the broker 127.0.0.1:") &&
			      strstr(out, "refused the connection: Connection Refused: not "
					  "authorised"), "%s", out);
	ck_assert_msg(strstr(out, "holds API keys and the MQTT password and can be read by other "
				  "users (mode 0644)"), "%s", out);
	ck_assert_msg(!strstr(out, "not-the-pass-99"), "the password is printed: %s", out);
	write_mqtt_config(&np, bport, "");
	rc = tu_run(out, sizeof(out), "serve --config '%s'", np.config);
	ck_assert_msg(rc == 65 && strstr(out, "not authorised"), "exit %d: %s", rc, out);

	write_mqtt_config(&np, bport, "username = test-node\npassword = node-pass-123\n");
	sv_start(&np);
	wait_topic(&seen, "stratum/test-node/status", "online", 10, NULL, 0);
	wait_topic(&seen, "stratum/test-node/mk3s/status", "Operational", 10, NULL, 0);
	sv_stop(&np);
	log = tu_slurp(np.log, &len);
	ck_assert_msg(!strstr(log, "node-pass-123"), "the password is logged: %s", log);
	free(log);
	watch_stop(mq, &seen);
	broker_stop(broker);
}
END_TEST

/* enqueue downloads nothing by default, and then only from the hosts of
 * download_hosts: another host, another port, or a redirect to either is
 * refused before any byte is fetched from it. */
START_TEST(test_mqtt_downloads)
{
	struct node_proc np;
	struct file_server allowed, other;
	struct mqtt_seen seen;
	struct mosquitto *mq;
	char out[2048], cmd[1024], extra[256], redirect[256];
	int bport;
	pid_t broker;

	if (!have_broker("MQTT downloads"))
		return;
	file_server_start(&allowed, "G28\nG1 X5\n");
	file_server_start(&other, "G28\n");
	broker = node_on_broker(&np, &bport, "", &seen, &mq);
#define ENQUEUE(id, port, file)                                                               \
	snprintf(cmd, sizeof(cmd), "{\"id\":\"" id "\",\"command\":\"enqueue\",\"key\":\"" KEY_CTL  \
		 "\",\"url\":\"http://%s/" file "\"}", port)
	snprintf(extra, sizeof(extra), "127.0.0.1:%d", allowed.port);
	ENQUEUE("d-1", extra, "part.gcode");
	mqtt_command(mq, &seen, cmd, "\"d-1\"", out, sizeof(out));
	ck_assert_msg(strstr(out, "downloads are off: [mqtt] download_hosts lists no host"), "%s",
		      out);
	ck_assert_int_eq(allowed.served, 0);
	sv_stop(&np);

	snprintf(extra, sizeof(extra), "download_hosts = localhost, 127.0.0.1:%d\n", allowed.port);
	write_mqtt_config(&np, bport, extra);
	sv_start(&np);
	wait_topic(&seen, "stratum/test-node/status", "online", 10, NULL, 0);
	snprintf(extra, sizeof(extra), "127.0.0.1:%d", other.port);
	ENQUEUE("d-2", extra, "part.gcode");
	mqtt_command(mq, &seen, cmd, "\"d-2\"", out, sizeof(out));
	snprintf(extra, sizeof(extra), "127.0.0.1:%d is not in [mqtt] download_hosts", other.port);
	ck_assert_msg(strstr(out, extra), "%s", out);
	/* a bare host name allows the scheme's own port (80) only */
	snprintf(extra, sizeof(extra), "localhost:%d", other.port);
	ENQUEUE("d-3", extra, "part.gcode");
	mqtt_command(mq, &seen, cmd, "\"d-3\"", out, sizeof(out));
	ck_assert_msg(strstr(out, "is not in [mqtt] download_hosts"), "%s", out);
	/* a redirect from the allowed host to another is checked before it is followed */
	snprintf(redirect, sizeof(redirect), "http://127.0.0.1:%d/evil.gcode", other.port);
	allowed.redirect = redirect;
	snprintf(extra, sizeof(extra), "127.0.0.1:%d", allowed.port);
	ENQUEUE("d-4", extra, "part.gcode");
	mqtt_command(mq, &seen, cmd, "\"d-4\"", out, sizeof(out));
	ck_assert_msg(strstr(out, "redirected to http://127.0.0.1:") &&
			  strstr(out, "is not in [mqtt] download_hosts"),
		      "%s", out);
	ck_assert_int_eq(allowed.served, 1);
	ck_assert_int_eq(other.served, 0);
	allowed.redirect = NULL;
	ENQUEUE("d-5", extra, "part.gcode");
	mqtt_command(mq, &seen, cmd, "\"d-5\"", out, sizeof(out));
	ck_assert_msg(strstr(out, "\"ok\":true") && strstr(out, "\"job\":"), "%s", out);
	ck_assert_int_eq(allowed.served, 2);
#undef ENQUEUE
	watch_stop(mq, &seen);
	sv_stop(&np);
	file_server_stop(&allowed);
	file_server_stop(&other);
	broker_stop(broker);
}
END_TEST

/* Every occurrence of from in text replaced by to, into out (cap bytes). */
static void replace_all(char *out, size_t cap, const char *text, const char *from, const char *to)
{
	size_t used = 0, fl = strlen(from);
	const char *at;

	while ((at = strstr(text, from)) != NULL) {
		used += (size_t)snprintf(out + used, cap - used, "%.*s%s", (int)(at - text), text, to);
		ck_assert(used < cap);
		text = at + fl;
	}
	used += (size_t)snprintf(out + used, cap - used, "%s", text);
	ck_assert(used < cap);
}

/* The broker of docs/serve.md ("What the broker must restrict"), its two
 * files as they stand there: the node connects over TLS with its password,
 * the controller's signed command is answered, another node's user cannot
 * command it; the broker's host name is checked unless tls_insecure = 1. */
START_TEST(test_mqtt_broker_example)
{
	static char doc[1 << 17], doc2[1 << 17];
	struct node_proc np;
	struct mqtt_seen seen, intruder_seen;
	struct mosquitto *mq, *intruder;
	char dir[512], etc[600], conf[4096], text[1024], cmd[1024], out[4096], ca[700];
	const char *conf_doc, *acl_doc;
	int bport, rc, results;
	pid_t broker;
	size_t len;
	char *log;

	if (!have_broker("MQTT broker example"))
		return;
	if (access("/usr/bin/mosquitto_passwd", X_OK) || access("/usr/bin/openssl", X_OK)) {
		printf("serve: MQTT broker example test skipped: no mosquitto_passwd or openssl\n");
		return;
	}
	conf_doc = tu_read_between("docs/serve.md", doc, sizeof(doc),
				   "# /etc/mosquitto/conf.d/stratum.conf\n", "```");
	acl_doc = tu_read_between("docs/serve.md", doc2, sizeof(doc2),
				  "# /etc/mosquitto/stratum.acl\n", "```");
	snprintf(dir, sizeof(dir), "%s", tu_path("etc-mosquitto"));
	snprintf(etc, sizeof(etc), "%s/", dir);
	rc = tu_sh(out, sizeof(out),
		   "{ mkdir -p '%s/certs' && cd '%s/certs' && printf 'subjectAltName=IP:127.0.0.1\\n' "
		   "> san.ext && openssl req -x509 -newkey ec -pkeyopt ec_paramgen_curve:prime256v1 "
		   "-nodes -keyout ca.key -out ca.crt -days 2 -subj /CN=test-ca && openssl req "
		   "-newkey ec -pkeyopt ec_paramgen_curve:prime256v1 -nodes -keyout broker.key -out "
		   "broker.csr -subj /CN=127.0.0.1 && openssl x509 -req -in broker.csr -CA ca.crt "
		   "-CAkey ca.key -CAcreateserial -days 2 -extfile san.ext -out broker.crt && "
		   "mosquitto_passwd -c -b ../stratum.passwd test-node node-pass-123 && "
		   "mosquitto_passwd -b ../stratum.passwd controller ctl-pass-123 && "
		   "mosquitto_passwd -b ../stratum.passwd farm-2 other-pass-123; }", dir, dir);
	ck_assert_msg(rc == 0, "%s", out);
	bport = free_port();
	replace_all(text, sizeof(text), conf_doc, "/etc/mosquitto/", etc);
	snprintf(cmd, sizeof(cmd), "listener %d 127.0.0.1", bport);
	replace_all(conf, sizeof(conf), text, "listener 8883", cmd);
	snprintf(text, sizeof(text), "%sstratum.acl", etc);
	tu_write_str(text, acl_doc);
	broker = broker_start(bport, conf);
	snprintf(ca, sizeof(ca), "%scerts/ca.crt", etc);
	mq = watch_start_tls(&seen, bport, "controller", "ctl-pass-123", "stratum/#", ca);

	snprintf(text, sizeof(text), "username = test-node\npassword = node-pass-123\ntls = 1\n"
				     "ca_file = %s\n", ca);
	write_mqtt_config(&np, bport, text);
	sv_start(&np);
	wait_topic(&seen, "stratum/test-node/status", "online", 10, NULL, 0);
	/* Another node's user publishes a command with a good key: the broker drops it. */
	intruder = watch_start_tls(&intruder_seen, bport, "farm-2", "other-pass-123",
				   "stratum/farm-2/#", ca);
	watch_send(intruder, CMD_TOPIC, "{\"id\":\"x-1\",\"command\":\"pause\",\"key\":\"" KEY_CTL
					"\"}");
	usleep(300000);
	pthread_mutex_lock(&seen.mu);
	results = seen.results;
	pthread_mutex_unlock(&seen.mu);
	snprintf(text, sizeof(text), "{\"id\":\"x-2\",\"command\":\"pause\",\"time\":%lld}",
		 (long long)time(NULL));
	sign(cmd, sizeof(cmd), CMD_TOPIC, text, "operator", KEY_CTL);
	mqtt_command(mq, &seen, cmd, "\"x-2\"", out, sizeof(out));
	ck_assert_msg(strstr(out, "no job"), "%s", out);
	pthread_mutex_lock(&seen.mu);
	ck_assert_int_eq(seen.results, results + 1);
	pthread_mutex_unlock(&seen.mu);
	watch_stop(intruder, &intruder_seen);
	sv_stop(&np);
	log = tu_slurp(np.log, &len);
	ck_assert_msg(!strstr(log, "x-1"), "the intruder's command arrived: %s", log);
	free(log);

	/* The certificate names 127.0.0.1, not localhost: refused, unless insecure. */
	snprintf(text, sizeof(text), "username = test-node\npassword = node-pass-123\ntls = 1\n"
				     "ca_file = %s\n", ca);
	snprintf(conf, sizeof(conf), ONE_PRINTER "\n[mqtt]\nhost = localhost\nport = %d\n%s",
		 bport, text);
	sv_write_config(&np, conf, 8);
	sv_start(&np);
	sv_stop(&np);
	log = tu_slurp(np.log, &len);
	ck_assert_msg(strstr(log + np.log_end, "mqtt: cannot reach localhost:") &&
			      strstr(log + np.log_end, "TLS"), "%s", log + np.log_end);
	free(log);
	snprintf(conf + strlen(conf), sizeof(conf) - strlen(conf), "tls_insecure = 1\n");
	sv_write_config(&np, conf, 8);
	sv_start(&np);
	wait_topic(&seen, "stratum/test-node/status", "online", 10, NULL, 0);
	sv_stop(&np);
	watch_stop(mq, &seen);
	broker_stop(broker);
}
END_TEST

/* PRINTER/temperatures is /api/printer's temperature: a Marlin printer's
 * offsets, and the Creator Pro's tool1 with the target it was given. */
START_TEST(test_mqtt_temperatures)
{
	struct node_proc np;
	struct mqtt_seen seen;
	struct mosquitto *mq;
	struct resp r;
	char text[1024];
	int port, status = 0;
	pid_t broker;

	if (!have_broker("test_mqtt_temperatures"))
		return;
	port = free_port();
	broker = anon_broker_start(port);
	snprintf(text, sizeof(text), "[printer mk3s]\nprofile = prusa-i3-mk3s\nport = sim\n"
		 "sim_speedup = 1000\n[printer cp]\nprofile = flashforge-creator-pro\n"
		 "port = sim\nsim_speedup = 1000\n\n[mqtt]\nhost = 127.0.0.1\nport = %d\n"
		 "keepalive = 5\n", port);
	sv_write_config(&np, text, 8);
	sv_start(&np);
	mq = watch_start(&seen, port, NULL, NULL, "stratum/test-node/#");
	wait_topic(&seen, "stratum/test-node/status", "online", 10, NULL, 0);
	/* the simulated printers connect on their own; offsets need them operational */
	for (int i = 0; i < 250 && status != 204; i++) {
		sv_http(np.port, "POST", "/p/mk3s/api/printer/tool", "X-Api-Key: " KEY_CTL,
			"{\"command\":\"offset\",\"offsets\":{\"tool0\":10}}", &r);
		status = r.status;
		sv_resp_free(&r);
		if (status != 204)
			usleep(20000);
	}
	ck_assert_int_eq(status, 204);
	sv_expect(np.port, "POST", "/p/mk3s/api/printer/bed", "X-Api-Key: " KEY_CTL,
		  "{\"command\":\"offset\",\"offset\":-5}", 204);
	wait_topic(&seen, "stratum/test-node/mk3s/temperatures", "\"offset\":-5}", 10, text,
		   sizeof(text));
	ck_assert_msg(strstr(text, "\"offset\":10}") && !strstr(text, "tool1"), "%s", text);
	sv_expect(np.port, "POST", "/p/cp/api/printer/tool", "X-Api-Key: " KEY_CTL,
		  "{\"command\":\"target\",\"targets\":{\"tool1\":150}}", 204);
	wait_topic(&seen, "stratum/test-node/cp/temperatures", "\"target\":150", 10, text,
		   sizeof(text));
	ck_assert_msg(strstr(text, "\"tool1\":{"), "%s", text);
	watch_stop(mq, &seen);
	sv_stop(&np);
	broker_stop(broker);
}
END_TEST

/* The names of the jobs waiting in a list command's answer, in order,
 * "a.gcode,b.gcode". */
static const char *waiting_names(const char *answer)
{
	static char names[256];
	json_t *o = json_loads(answer, 0, NULL), *j;
	size_t i, len = 0;

	ck_assert_msg(o, "not JSON (cut?): %s", answer);
	names[0] = '\0';
	json_array_foreach(json_object_get(o, "waiting"), i, j)
		len += (size_t)snprintf(names + len, sizeof(names) - len, "%s%s", i ? "," : "",
					json_string_value(json_object_get(j, "name")));
	json_decref(o);
	return names;
}

/* The queue over MQTT, as /api/stratum/queue has it: list, move, cancel
 * and requeue a job, with the control key (without it, refused). */
START_TEST(test_mqtt_queue_commands)
{
	struct node_proc np;
	struct mqtt_seen seen;
	struct mosquitto *mq;
	char out[2048];
	long long hold, c;
	int bport;
	pid_t broker;

	if (!have_broker("MQTT queue commands"))
		return;
	broker = node_on_broker(&np, &bport, "", &seen, &mq);
	hold = sv_print_text(np.port, "", "hold.gcode", "G28\nG4 P20000\n");
	sv_wait_state(np.port, "", hold, "printing", 10);
	sv_print_text(np.port, "", "a.gcode", "G28\n");
	sv_print_text(np.port, "", "b.gcode", "G28\n");
	c = sv_print_text(np.port, "", "c.gcode", "G28\n");
	mqtt_command(mq, &seen, "{\"id\":\"q-1\",\"command\":\"list\",\"key\":\"" KEY_CTL "\"}",
		     "\"q-1\"", out, sizeof(out));
	ck_assert_str_eq(waiting_names(out), "a.gcode,b.gcode,c.gcode");
	mqtt_command(mq, &seen, "{\"id\":\"q-2\",\"command\":\"move\",\"job\":4,\"position\":1}",
		     "\"q-2\"", out, sizeof(out));
	ck_assert_msg(strstr(out, "a key with the control role is needed"), "%s", out);
	mqtt_command(mq, &seen,
		     "{\"id\":\"q-3\",\"command\":\"move\",\"job\":4,\"position\":1,"
		     "\"key\":\"" KEY_CTL "\"}",
		     "\"q-3\"", out, sizeof(out));
	ck_assert_msg(strstr(out, "\"ok\":true"), "%s", out);
	mqtt_command(mq, &seen,
		     "{\"id\":\"q-4\",\"command\":\"move\",\"job\":1,\"position\":1,"
		     "\"key\":\"" KEY_CTL "\"}",
		     "\"q-4\"", out, sizeof(out));
	ck_assert_msg(strstr(out, "only a queued job can be moved"), "%s", out);
	mqtt_command(mq, &seen,
		     "{\"id\":\"q-5\",\"command\":\"cancel\",\"job\":3,"
		     "\"key\":\"" KEY_CTL "\"}",
		     "\"q-5\"", out, sizeof(out));
	ck_assert_msg(strstr(out, "\"ok\":true"), "%s", out);
	ck_assert_str_eq(sv_job_state(np.port, "", 3, NULL), "cancelled");
	ck_assert_str_eq(sv_job_state(np.port, "", hold, NULL), "printing");
	mqtt_command(mq, &seen,
		     "{\"id\":\"q-6\",\"command\":\"requeue\",\"job\":3,"
		     "\"key\":\"" KEY_CTL "\"}",
		     "\"q-6\"", out, sizeof(out));
	ck_assert_msg(strstr(out, "\"ok\":true") && strstr(out, "\"job\":5"), "%s", out);
	mqtt_command(mq, &seen, "{\"id\":\"q-7\",\"command\":\"list\",\"key\":\"" KEY_CTL "\"}",
		     "\"q-7\"", out, sizeof(out));
	ck_assert_str_eq(waiting_names(out), "c.gcode,a.gcode,b.gcode");
	ck_assert_int_eq(c, 4);
	watch_stop(mq, &seen);
	sv_stop(&np);
	broker_stop(broker);
}
END_TEST

void serve_mqtt_tcases(Suite *s)
{
	TCase *tc = tcase_create("mqtt");

	tcase_set_timeout(tc, 60);
	tcase_add_test(tc, test_mqtt_config_errors);
	tcase_add_test(tc, test_mqtt_command_keys);
	serve_mqtt_name_tests(tc);
	tcase_add_test(tc, test_mqtt_password);
	tcase_add_test(tc, test_mqtt_downloads);
	tcase_add_test(tc, test_mqtt_broker_example);
	tcase_add_test(tc, test_mqtt_temperatures);
	tcase_add_test(tc, test_mqtt_queue_commands);
	suite_add_tcase(s, tc);
}
