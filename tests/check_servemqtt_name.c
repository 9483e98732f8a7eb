/*
 * check_servemqtt_name.c - the farm node's name on a shared MQTT broker,
 * part of the serve suite (check_servemqtt.c, the same "mqtt" case): a
 * second node of one name is refused, a node whose client id another takes
 * while it runs or while the broker is down yields it instead of knocking
 * the other off.  Each test runs its own mosquitto on loopback.
 */
#include <check.h>
#include <pthread.h>
#include <signal.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>
#include <sys/stat.h>
#include <unistd.h>

#include "mqtttest.h"
#include "servetest.h"
#include "suites.h"
#include "testutil.h"

/* A second node with a name another node holds on the broker is refused
 * (exit 65) without knocking the first off or opening its printers; a
 * stale "online" with no node behind it does not block the name. */
START_TEST(test_mqtt_same_name)
{
	struct node_proc np;
	struct mqtt_seen seen;
	struct mosquitto *mq;
	char out[4096], text[1024], dir[512], conf[600];
	int bport, rc;
	pid_t broker;
	size_t len;
	char *log;

	if (!have_broker("MQTT same name"))
		return;
	broker = node_on_broker(&np, &bport, "", &seen, &mq);
	/* The same name from another config and data directory. */
	snprintf(dir, sizeof(dir), "%s", tu_path("second"));
	mkdir(dir, 0700);
	snprintf(conf, sizeof(conf), "%s/node.ini", dir);
	snprintf(text, sizeof(text), "[node]\nname = test-node\nlisten = 127.0.0.1:0\n"
				     "data_dir = data\n[key k]\nkey = " KEY_CTL "\nroles = control\n"
				     ONE_PRINTER "[mqtt]\nhost = 127.0.0.1\nport = %d\n", bport);
	tu_write_str(conf, text);
	chmod(conf, 0600);
	rc = tu_run(out, sizeof(out), "serve --config '%s'", conf);
	ck_assert_msg(rc == 65, "exit %d: %s", rc, out);
	ck_assert_msg(strstr(out, "mqtt: another node named test-node is connected to the broker "
				  "127.0.0.1:") && strstr(out, "give this node another name"),
		      "%s", out);
	ck_assert_msg(!strstr(out, "test-instant"), "the refused node opened its printer: %s", out);
	/* The first node was never off the broker and still answers commands. */
	mqtt_command(mq, &seen, "{\"id\":\"n-1\",\"command\":\"pause\",\"key\":\"" KEY_CTL "\"}",
		     "\"n-1\"", out, sizeof(out));
	ck_assert_msg(strstr(out, "no job"), "%s", out);
	sv_stop(&np);
	log = tu_slurp(np.log, &len);
	ck_assert_msg(!strstr(log, "connection lost"), "%s", log);
	ck_assert_msg(strstr(log, "a node asked whether the name test-node is held"), "%s", log);
	free(log);
	/* Stopped cleanly: offline.  A stale online (a node the broker has not yet
	 * seen die) delays the start by the ping's wait only. */
	wait_topic(&seen, "stratum/test-node/status", "offline", 10, NULL, 0);
	ck_assert_int_eq(mosquitto_publish(mq, NULL, "stratum/test-node/status", 6, "online", 1,
					   true), 0);
	wait_topic(&seen, "stratum/test-node/status", "online", 10, NULL, 0);
	sv_start(&np);
	wait_topic(&seen, "stratum/test-node/mk3s/status", "Operational", 10, NULL, 0);
	sv_stop(&np);
	log = tu_slurp(np.log, &len);
	ck_assert_msg(strstr(log, "no node answered; taking the name"), "%s", log);
	free(log);
	watch_stop(mq, &seen);
	broker_stop(broker);
}
END_TEST

/* A client that takes a node's client id, as a second node of its name
 * would: it says online and answers pings; kicks counts how often the
 * broker dropped it for another client with its id; ready, that its status
 * is on the broker and its ping subscription acknowledged. */
struct impostor {
	int kicks;
	bool ready;
	pthread_mutex_t mu;
};

static void impostor_connect(struct mosquitto *mosq, void *ctx, int rc)
{
	(void)ctx;
	if (rc)
		return;
	mosquitto_publish(mosq, NULL, "stratum/test-node/status", 6, "online", 1, true);
	mosquitto_subscribe(mosq, NULL, "stratum/test-node/ping", 0);
}

/* The SUBACK comes after the broker took the status published before the
 * subscription (one connection's packets are handled in order). */
static void impostor_subscribed(struct mosquitto *mosq, void *ctx, int mid, int n, const int *qos)
{
	struct impostor *im = ctx;

	(void)mosq, (void)mid, (void)n, (void)qos;
	pthread_mutex_lock(&im->mu);
	im->ready = true;
	pthread_mutex_unlock(&im->mu);
}

static void impostor_message(struct mosquitto *mosq, void *ctx, const struct mosquitto_message *m)
{
	char answer[200];

	(void)ctx;
	snprintf(answer, sizeof(answer), "%.*s: the impostor", m->payloadlen > 64 ? 64 : m->payloadlen,
		 (const char *)m->payload);
	mosquitto_publish(mosq, NULL, "stratum/test-node/pong", (int)strlen(answer), answer, 0, false);
}

static void impostor_disconnect(struct mosquitto *mosq, void *ctx, int rc)
{
	struct impostor *im = ctx;

	(void)mosq;
	pthread_mutex_lock(&im->mu);
	im->kicks += rc != 0;
	pthread_mutex_unlock(&im->mu);
}

/* Hold (SIGSTOP) or release (SIGCONT) the node: what a test sets up on the
 * broker while the node is held is there before the node looks, however
 * loaded the machine is. */
static void node_hold(const struct node_proc *np, bool hold)
{
	ck_assert_int_eq(kill(np->pid, hold ? SIGSTOP : SIGCONT), 0);
}

/*
 * The impostor, connected to the broker at port, holding the name of the
 * node np (held meanwhile, so it cannot take the name first: it would knock
 * the impostor off once, which is not what the tests are about) before
 * this returns.  End it with expect_node_yields.
 */
static struct mosquitto *impostor_start(struct impostor *im, int port, struct node_proc *np)
{
	struct mosquitto *other;
	bool ready = false;

	pthread_mutex_init(&im->mu, NULL);
	im->kicks = 0;
	im->ready = false;
	other = mosquitto_new("stratum-test-node", false, im);
	ck_assert(other);
	mosquitto_connect_callback_set(other, impostor_connect);
	mosquitto_subscribe_callback_set(other, impostor_subscribed);
	mosquitto_message_callback_set(other, impostor_message);
	mosquitto_disconnect_callback_set(other, impostor_disconnect);
	mosquitto_reconnect_delay_set(other, 1, 1, false);
	ck_assert_int_eq(mosquitto_connect(other, "127.0.0.1", port, 30), 0);
	ck_assert_int_eq(mosquitto_loop_start(other), 0);
	for (int i = 0; i < 400 && !ready; i++) {
		usleep(25000);
		pthread_mutex_lock(&im->mu);
		ready = im->ready;
		pthread_mutex_unlock(&im->mu);
	}
	ck_assert_msg(ready, "the impostor did not get onto the broker within 10 s");
	node_hold(np, false);
	return other;
}

/* Wait for the node's log to say it found the impostor and turned MQTT
 * off; then the impostor must keep its connection (the node would be back
 * within 1 s). */
static void expect_node_yields(struct node_proc *np, struct impostor *im, struct mosquitto *other)
{
	char *log = NULL;
	size_t len;
	int kicks;

	for (int i = 0; i < 200; i++) {
		free(log);
		log = tu_slurp(np->log, &len);
		if (strstr(log + np->log_end, "MQTT is off until the node restarts"))
			break;
		usleep(50000);
	}
	ck_assert_msg(strstr(log + np->log_end, "mqtt: another node named test-node is connected "
						"to the broker") &&
			      strstr(log + np->log_end, "the impostor") &&
			      strstr(log + np->log_end, "MQTT is off until the node restarts"),
		      "%s", log + np->log_end);
	free(log);
	sleep(2);
	pthread_mutex_lock(&im->mu);
	kicks = im->kicks;
	pthread_mutex_unlock(&im->mu);
	ck_assert_int_eq(kicks, 0);
	mosquitto_disconnect(other);
	mosquitto_loop_stop(other, false);
	mosquitto_destroy(other);
	pthread_mutex_destroy(&im->mu);
}

/* A running node whose client id another client takes (two nodes of one
 * name that both found it free) checks the name before it reconnects,
 * finds the other, and stays off the broker instead of knocking it off. */
START_TEST(test_mqtt_name_taken_while_running)
{
	struct node_proc np;
	struct mqtt_seen seen;
	struct mosquitto *mq, *other;
	struct impostor im;
	int bport;
	pid_t broker;

	if (!have_broker("MQTT name taken while running"))
		return;
	broker = node_on_broker(&np, &bport, "", &seen, &mq);
	node_hold(&np, true);
	other = impostor_start(&im, bport, &np);
	expect_node_yields(&np, &im, other);
	sv_stop(&np);
	watch_stop(mq, &seen);
	broker_stop(broker);
}
END_TEST

/* A broker that is down when the node starts: the node runs, and checks
 * its name once the broker is there; a node that took the name meanwhile
 * keeps it.  Then, with the name free, it connects. */
START_TEST(test_mqtt_broker_later)
{
	struct node_proc np;
	struct mqtt_seen seen;
	struct mosquitto *mq, *other;
	struct impostor im;
	int bport = free_port();
	pid_t broker;

	if (!have_broker("MQTT broker later"))
		return;
	write_mqtt_config(&np, bport, "");
	sv_start(&np);
	node_hold(&np, true);
	broker = anon_broker_start(bport);
	other = impostor_start(&im, bport, &np);
	expect_node_yields(&np, &im, other);
	sv_stop(&np);
	/* a new broker (nothing retained): the name is free when it comes */
	broker_stop(broker);
	sv_start(&np);
	broker = anon_broker_start(bport);
	mq = watch_start(&seen, bport, NULL, NULL, "stratum/test-node/#");
	wait_topic(&seen, "stratum/test-node/status", "online", 10, NULL, 0);
	wait_topic(&seen, "stratum/test-node/mk3s/status", "Operational", 10, NULL, 0);
	watch_stop(mq, &seen);
	sv_stop(&np);
	broker_stop(broker);
}
END_TEST

/* The tests of the "mqtt" case on the node's name, in their place. */
void serve_mqtt_name_tests(TCase *tc)
{
	tcase_add_test(tc, test_mqtt_same_name);
	tcase_add_test(tc, test_mqtt_name_taken_while_running);
	tcase_add_test(tc, test_mqtt_broker_later);
}
