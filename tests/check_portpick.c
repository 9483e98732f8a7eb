/*
 * check_portpick.c - `--port auto` (host/portpick.h) on made-up port
 * enumerations and profiles: no hardware is needed to decide which port a
 * printer is on.
 */
#include <check.h>
#include <string.h>

#include "portpick.h"
#include "suites.h"

static struct profile *make_profile(const char *id, const char *usb_ids)
{
	char text[256], origin[64];
	struct profile *p = NULL;
	struct st_error err = {0};

	snprintf(text, sizeof(text), "usb_ids = %s\n", usb_ids);
	snprintf(origin, sizeof(origin), "/tmp/%s.ini", id);
	ck_assert_msg(profile_load_buffer(text, strlen(text), origin, &p, &err) == 0, "%s",
		      err.msg);
	return p;
}

/* A USB port (vid >= 0) or an on-board UART. */
static struct xport_port_info port(char *name, char *by_id, int vid, int pid, char *serial)
{
	return (struct xport_port_info){.name = name,
					.by_id = by_id,
					.transport = vid >= 0 ? XPORT_TRANSPORT_USB
							      : XPORT_TRANSPORT_NATIVE,
					.usb_vid = vid,
					.usb_pid = pid,
					.serial = serial};
}

struct world {
	struct profile *ender, *mk3, *generic;
	const struct profile *all[3];
};

static void world_init(struct world *w)
{
	w->ender = make_profile("ender", "1a86:7523");
	w->mk3 = make_profile("mk3", "2c99:0002");
	w->generic = make_profile("generic", "");
	w->all[0] = w->ender;
	w->all[1] = w->mk3;
	w->all[2] = w->generic;
}

static void world_free(struct world *w)
{
	profile_free(w->ender);
	profile_free(w->mk3);
	profile_free(w->generic);
}

START_TEST(profile_match_prefers_by_id)
{
	struct world w;
	struct portpick_result r;
	struct st_error err = {0};
	struct xport_port_info ports[] = {
	    port("/dev/ttyACM0", "/dev/serial/by-id/usb-Prusa_Research_Original_Prusa_i3_MK3-if00",
		 0x2c99, 0x0002, "CZPX1"),
	    port("/dev/ttyS0", NULL, -1, -1, NULL),
	    port("/dev/ttyUSB0", NULL, 0x1a86, 0x7523, NULL),
	};

	world_init(&w);
	ck_assert_int_eq(portpick_choose(w.mk3, w.all, 3, ports, 3, &r, &err), 0);
	ck_assert_int_eq(r.index, 0);
	ck_assert_str_eq(r.path, ports[0].by_id);
	ck_assert_ptr_eq(r.profile, w.mk3);
	ck_assert_msg(strstr(r.why, "2c99:0002 is in mk3's usb_ids"), "%s", r.why);
	/* The Ender's board has no by-id name: its device name, said so. */
	ck_assert_int_eq(portpick_choose(w.ender, w.all, 3, ports, 3, &r, &err), 0);
	ck_assert_int_eq(r.index, 2);
	ck_assert_str_eq(r.path, "/dev/ttyUSB0");
	ck_assert_msg(strstr(r.why, "no /dev/serial/by-id/ name"), "%s", r.why);
	/* No printer named: two profiles claim a port each, so it is ambiguous. */
	ck_assert_int_eq(portpick_choose(NULL, w.all, 3, ports, 3, &r, &err), ST_ERR_IO);
	ck_assert_int_eq(r.index, -1);
	ck_assert_ptr_null(r.path);
	ck_assert_msg(strstr(r.why, "2 ports match the printer profiles") &&
			      strstr(r.why, "/dev/ttyUSB0 (1a86:7523)") &&
			      strstr(r.why, "serial CZPX1"),
		      "%s", r.why);
	world_free(&w);
}
END_TEST

START_TEST(two_boards_refused)
{
	struct world w;
	struct portpick_result r;
	struct st_error err = {0};
	struct xport_port_info ports[] = {
	    port("/dev/ttyUSB0", "/dev/serial/by-id/usb-1a86_USB_Serial-if00-port0", 0x1a86,
		 0x7523, NULL),
	    port("/dev/ttyUSB1", "/dev/serial/by-id/usb-1a86_USB_Serial_B-if00-port0", 0x1a86,
		 0x7523, NULL),
	};

	world_init(&w);
	ck_assert_int_eq(portpick_choose(w.ender, w.all, 3, ports, 2, &r, &err), ST_ERR_IO);
	ck_assert_msg(strstr(r.why, "2 ports match ender") &&
			      strstr(r.why, "usb-1a86_USB_Serial-if00-port0") &&
			      strstr(r.why, "usb-1a86_USB_Serial_B-if00-port0") &&
			      strstr(r.why, "Give --port"),
		      "%s", r.why);
	ck_assert_msg(strstr(err.msg, "--port auto: 2 ports match ender"), "%s", err.msg);
	world_free(&w);
}
END_TEST

START_TEST(nothing_fits_explained)
{
	struct world w;
	struct portpick_result r;
	struct st_error err = {0};
	struct xport_port_info ports[] = {
	    port("/dev/ttyS0", NULL, -1, -1, NULL),
	    port("/dev/ttyUSB0", NULL, 0x0403, 0x6001, "A50285BI"),
	    port("/dev/ttyUSB1", NULL, 0x10c4, 0xea60, NULL),
	};

	world_init(&w);
	/* The printer's ids are not there. */
	ck_assert_int_eq(portpick_choose(w.mk3, w.all, 3, ports, 3, &r, &err), ST_ERR_IO);
	ck_assert_msg(strstr(r.why, "no port has a USB id that printer mk3 lists (2c99:0002)") &&
			      strstr(r.why, "/dev/ttyUSB0 (0403:6001, serial A50285BI)") &&
			      strstr(r.why, "usb_ids in /tmp/mk3.ini"),
		      "%s", r.why);
	/* No profile: two unknown USB adapters, nothing to tell them apart. */
	ck_assert_int_eq(portpick_choose(NULL, w.all, 3, ports, 3, &r, &err), ST_ERR_IO);
	ck_assert_msg(strstr(r.why, "no printer profile lists the USB id of any of the 2"), "%s",
		      r.why);
	/* One unknown USB adapter and a UART: the adapter, with the reason. */
	ck_assert_int_eq(portpick_choose(w.generic, w.all, 3, ports, 2, &r, &err), 0);
	ck_assert_str_eq(r.path, "/dev/ttyUSB0");
	ck_assert_ptr_null(r.profile);
	ck_assert_msg(strstr(r.why, "the only USB serial port (0403:6001"), "%s", r.why);
	/* Only a UART: never chosen. */
	ck_assert_int_eq(portpick_choose(NULL, w.all, 3, ports, 1, &r, &err), ST_ERR_IO);
	ck_assert_msg(strstr(r.why, "no USB serial port found; found: /dev/ttyS0"), "%s", r.why);
	/* Nothing at all. */
	ck_assert_int_eq(portpick_choose(w.mk3, w.all, 3, NULL, 0, &r, &err), ST_ERR_IO);
	ck_assert_msg(strstr(r.why, "no serial ports found"), "%s", r.why);
	world_free(&w);
}
END_TEST

Suite *portpick_suite(void)
{
	Suite *s = suite_create("portpick");
	TCase *tc = tcase_create("portpick");

	tcase_add_test(tc, profile_match_prefers_by_id);
	tcase_add_test(tc, two_boards_refused);
	tcase_add_test(tc, nothing_fits_explained);
	suite_add_tcase(s, tc);
	return s;
}
