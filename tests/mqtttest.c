/*
 * mqtttest.c - the helpers of mqtttest.h: a broker, a watching client and a
 * file server on loopback for the serve suite's MQTT tests.
 */
#include <arpa/inet.h>
#include <check.h>
#include <fcntl.h>
#include <netinet/in.h>
#include <pwd.h>
#include <signal.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>
#include <sys/socket.h>
#include <sys/wait.h>
#include <unistd.h>

#include "mqtttest.h"
#include "servetest.h"
#include "testutil.h"

/* A free loopback TCP port (bound once, then released). */
int free_port(void)
{
	struct sockaddr_in sa = {.sin_family = AF_INET};
	socklen_t len = sizeof(sa);
	int fd = socket(AF_INET, SOCK_STREAM, 0), port;

	inet_pton(AF_INET, "127.0.0.1", &sa.sin_addr);
	ck_assert(fd >= 0 && bind(fd, (struct sockaddr *)&sa, sizeof(sa)) == 0);
	ck_assert(getsockname(fd, (struct sockaddr *)&sa, &len) == 0);
	port = ntohs(sa.sin_port);
	close(fd);
	return port;
}

static void *file_server_main(void *arg)
{
	struct file_server *fs = arg;
	int c;

	while ((c = accept(fs->fd, NULL, NULL)) >= 0) {
		char req[4096], head[512];
		ssize_t n = recv(c, req, sizeof(req) - 1, 0);
		const char *body = fs->redirect ? "" : fs->body;
		int hn = fs->redirect
				 ? snprintf(head, sizeof(head), "HTTP/1.1 302 Found\r\nLocation: %s\r\n"
						"Content-Length: 0\r\nConnection: close\r\n\r\n",
					    fs->redirect)
				 : snprintf(head, sizeof(head), "HTTP/1.1 200 OK\r\nContent-Length: "
						"%zu\r\nConnection: close\r\n\r\n", strlen(body));

		if (n > 0) {
			send(c, head, (size_t)hn, MSG_NOSIGNAL);
			send(c, body, strlen(body), MSG_NOSIGNAL);
			fs->served++;
		}
		close(c);
	}
	return NULL;
}

void file_server_start(struct file_server *fs, const char *body)
{
	struct sockaddr_in sa = {.sin_family = AF_INET};
	socklen_t len = sizeof(sa);

	memset(fs, 0, sizeof(*fs));
	fs->body = body;
	fs->fd = socket(AF_INET, SOCK_STREAM, 0);
	inet_pton(AF_INET, "127.0.0.1", &sa.sin_addr);
	ck_assert(bind(fs->fd, (struct sockaddr *)&sa, sizeof(sa)) == 0 && listen(fs->fd, 4) == 0);
	getsockname(fs->fd, (struct sockaddr *)&sa, &len);
	fs->port = ntohs(sa.sin_port);
	ck_assert(pthread_create(&fs->thread, NULL, file_server_main, fs) == 0);
}

void file_server_stop(struct file_server *fs)
{
	shutdown(fs->fd, SHUT_RDWR);
	close(fs->fd);
	pthread_join(fs->thread, NULL);
}

void seen_message(struct mosquitto *mosq, void *ctx, const struct mosquitto_message *m)
{
	struct mqtt_seen *s = ctx;
	int i;

	(void)mosq;
	pthread_mutex_lock(&s->mu);
	for (i = 0; i < s->n && strcmp(s->topic[i], m->topic); i++)
		;
	if (i < SEEN_MAX) {
		if (i == s->n)
			s->n++;
		snprintf(s->topic[i], sizeof(s->topic[i]), "%s", m->topic);
		snprintf(s->payload[i], sizeof(s->payload[i]), "%.*s", m->payloadlen,
			 (const char *)m->payload);
	}
	if (strstr(m->topic, "/result"))
		s->results++;
	pthread_mutex_unlock(&s->mu);
}

/* Wait up to secs for topic's last payload to contain want; returns a copy in out. */
void wait_topic(struct mqtt_seen *s, const char *topic, const char *want, int secs,
		       char *out, size_t cap)
{
	char last[2048] = "";

	for (int t = 0; t < secs * 50; t++) {
		pthread_mutex_lock(&s->mu);
		for (int i = 0; i < s->n; i++)
			if (!strcmp(s->topic[i], topic))
				snprintf(last, sizeof(last), "%s", s->payload[i]);
		pthread_mutex_unlock(&s->mu);
		if (strstr(last, want)) {
			if (out)
				snprintf(out, cap, "%s", last);
			return;
		}
		usleep(20000);
	}
	ck_abort_msg("%s: '%s', waited for '%s'", topic, last, want);
}

bool have_broker(const char *test)
{
	if (!access(MOSQUITTO_BIN, X_OK))
		return true;
	printf("%s skipped: %s is not installed (make deps)\n", test, MOSQUITTO_BIN);
	return false;
}

pid_t anon_broker_start(int port)
{
	char conf[256];

	snprintf(conf, sizeof(conf), "listener %d 127.0.0.1\nallow_anonymous true\n"
				     "persistence false\n", port);
	return broker_start(port, conf);
}

pid_t broker_start(int port, const char *conf)
{
	struct passwd *me = getpwuid(getuid());
	char path[512], name[64], *text;
	pid_t pid;

	/* As root, mosquitto would become user mosquitto, who cannot read the
	 * test's files (password, certificates): stay who we are. */
	ck_assert(me != NULL);
	text = malloc(strlen(conf) + strlen(me->pw_name) + 8);
	ck_assert(text != NULL);
	sprintf(text, "user %s\n%s", me->pw_name, conf);
	snprintf(name, sizeof(name), "mosquitto-%d.conf", port);
	snprintf(path, sizeof(path), "%s", tu_path(name));
	tu_write_str(path, text);
	free(text);
	pid = fork();
	ck_assert(pid >= 0);
	if (!pid) {
		int fd = open("/dev/null", O_WRONLY);

		dup2(fd, 1);
		dup2(fd, 2);
		execl(MOSQUITTO_BIN, "mosquitto", "-c", path, (char *)NULL);
		_exit(127);
	}
	for (int i = 0; i < 250; i++) {
		struct sockaddr_in sa = {.sin_family = AF_INET, .sin_port = htons((uint16_t)port)};
		int fd = socket(AF_INET, SOCK_STREAM, 0), ok;

		inet_pton(AF_INET, "127.0.0.1", &sa.sin_addr);
		ok = connect(fd, (struct sockaddr *)&sa, sizeof(sa)) == 0;
		close(fd);
		if (ok)
			return pid;
		ck_assert_msg(waitpid(pid, NULL, WNOHANG) == 0, "mosquitto did not start with %s",
			      path);
		usleep(20000);
	}
	ck_abort_msg("mosquitto does not listen on %d", port);
	return pid;
}

void broker_stop(pid_t broker)
{
	kill(broker, SIGTERM);
	waitpid(broker, NULL, 0);
}

struct mosquitto *watch_start(struct mqtt_seen *seen, int port, const char *user,
			      const char *pass, const char *filter)
{
	return watch_start_tls(seen, port, user, pass, filter, NULL);
}

struct mosquitto *watch_start_tls(struct mqtt_seen *seen, int port, const char *user,
				  const char *pass, const char *filter, const char *cafile)
{
	struct mosquitto *mq;

	memset(seen, 0, sizeof(*seen));
	pthread_mutex_init(&seen->mu, NULL);
	mosquitto_lib_init();
	mq = mosquitto_new(NULL, true, seen);
	ck_assert(mq);
	if (user)
		ck_assert_int_eq(mosquitto_username_pw_set(mq, user, pass), 0);
	if (cafile)
		ck_assert_int_eq(mosquitto_tls_set(mq, cafile, NULL, NULL, NULL, NULL), 0);
	mosquitto_message_callback_set(mq, seen_message);
	ck_assert_int_eq(mosquitto_connect(mq, "127.0.0.1", port, 30), 0);
	ck_assert_int_eq(mosquitto_subscribe(mq, NULL, filter, 1), 0);
	ck_assert_int_eq(mosquitto_loop_start(mq), 0);
	return mq;
}

void watch_stop(struct mosquitto *mq, struct mqtt_seen *seen)
{
	mosquitto_disconnect(mq);
	mosquitto_loop_stop(mq, false);
	mosquitto_destroy(mq);
	mosquitto_lib_cleanup();
	pthread_mutex_destroy(&seen->mu);
}

void watch_send(struct mosquitto *mq, const char *topic, const char *payload)
{
	ck_assert_int_eq(mosquitto_publish(mq, NULL, topic, (int)strlen(payload), payload, 1, false),
			 0);
}

void mqtt_command(struct mosquitto *mq, struct mqtt_seen *seen, const char *payload,
		  const char *want, char *out, size_t cap)
{
	watch_send(mq, CMD_TOPIC, payload);
	wait_topic(seen, RESULT_TOPIC, want, 10, out, cap);
}

/* np's config: one test-instant printer and [mqtt] on the broker at port
 * with the lines extra. */
void write_mqtt_config(struct node_proc *np, int port, const char *extra)
{
	char text[2048];

	snprintf(text, sizeof(text), ONE_PRINTER "\n[mqtt]\nhost = 127.0.0.1\nport = %d\n"
					       "keepalive = 5\n%s", port, extra);
	sv_write_config(np, text, 8);
}

/* A broker, the node on it with the [mqtt] lines extra, and a client
 * watching the node's topics, once the node says it is online. */
pid_t node_on_broker(struct node_proc *np, int *port, const char *extra,
		     struct mqtt_seen *seen, struct mosquitto **mq)
{
	pid_t broker;

	*port = free_port();
	broker = anon_broker_start(*port);

	write_mqtt_config(np, *port, extra);
	sv_start(np);
	*mq = watch_start(seen, *port, NULL, NULL, "stratum/test-node/#");
	wait_topic(seen, "stratum/test-node/status", "online", 10, NULL, 0);
	return broker;
}
