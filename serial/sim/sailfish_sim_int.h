/*
 * sailfish_sim_int.h - what sailfish_sim.c (the link, the packet reader,
 * queries and the loop) and sailfish_sim_exec.c (the command processor and
 * heaters) share; nothing else includes it.  The contract is sailfish_sim.h.
 */
#ifndef STRATUM_SERIAL_SIM_SAILFISH_SIM_INT_H
#define STRATUM_SERIAL_SIM_SAILFISH_SIM_INT_H

#include <stdbool.h>
#include <stddef.h>
#include <stdint.h>

#include "s3g.h"
#include "st_grow.h"
#include "sailfish_sim.h"
#include "sim_util.h"

#define SF_PLANNER 16		/* Sailfish BLOCK_BUFFER_SIZE */
#define SF_TX_MAX (1u << 20)	/* reply backlog cap (bytes) */
#define SF_AMBIENT 25.0		/* degC */
#define SF_READY_BAND 2.0	/* heater "ready" within this of target (degC) */
#define SF_FW_VERSION 707	/* Sailfish 7.7 */
#define SF_VARIANT 0x80		/* SOFTWARE_VARIANT_ID of Sailfish */
#define SF_HOME_S 3.0		/* simulated homing time (s) */

/* Packet reader states and errors (Packet.hh). */
enum sf_ps { SF_PS_START, SF_PS_LEN, SF_PS_PAYLOAD, SF_PS_CRC, SF_PS_LAST };
enum sf_perr { SF_E_NONE, SF_E_NOISE, SF_E_LENGTH, SF_E_CRC, SF_E_TIMEOUT };

/* What the command processor is busy with. */
enum sf_mode { SF_READY, SF_DELAY, SF_HOMING, SF_WAIT_TOOL, SF_WAIT_PLATFORM };

struct sf_heater {
	double temp, target;	     /* degC */
	double heat_rate, cool_rate; /* degC per simulated s */
};

struct sim_sailfish {
	struct sim_sailfish_options o;
	int master, slave;
	char slave_path[128];
	FILE *log;
	bool own_log;
	uint64_t rng;

	uint8_t wire[4096];	/* host bytes still crossing the link */
	size_t wire_len;
	double in_t, out_t;	/* last byte in / last reply byte out (wall s) */
	long good_actions;	/* action packets received whole with a matching CRC */
	long good_queries;	/* query packets received whole with a matching CRC */
	bool rx_hit;		/* the packet being read lost or had a byte spoilt */
	uint64_t undetected;	/* packets so spoilt whose CRC-8 still matched */
	double boot_until;

	/* packet reader */
	int ps;
	int perr;
	uint8_t plen, pexp, pcrc;
	uint8_t payload[S3G_MAX_PAYLOAD];
	bool timer_on;
	double timer_start;

	/* replies */
	uint8_t *tx;
	size_t tx_len, tx_off, tx_cap;
	double tx_ready;	/* when the reply being written may start */
	bool soft_reset_pending;

	/* command buffer (ring) */
	uint8_t *cb;
	size_t cb_head, cb_len;

	/* machine */
	double planner_end[SF_PLANNER];
	size_t planner_n;
	int32_t pos[5];		/* steps */
	int tool;
	enum sf_mode mode;
	double mode_until;	/* delay/homing end, or wait time-out (wall s) */
	int wait_tool;
	bool paused;
	struct sf_heater heater[3]; /* tool 0, tool 1, platform */
	uint8_t build_state;
	uint32_t line, last_line;
	double build_t0;
	char build_name[32];
	uint64_t seq;
	unsigned resets;
	bool unplugged;

	double t_prev;
	_Atomic uint64_t machine_us; /* the machine's clock (sim_machine_add) */
	struct sim_thread th;
};


static inline uint32_t sf_rd32(const uint8_t *p)
{
	return (uint32_t)p[0] | (uint32_t)p[1] << 8 | (uint32_t)p[2] << 16 | (uint32_t)p[3] << 24;
}

static inline uint16_t sf_rd16(const uint8_t *p)
{
	return (uint16_t)(p[0] | p[1] << 8);
}


void sfsim_hard_reset(struct sim_sailfish *s, double now);
size_t sfsim_cb_peek(const struct sim_sailfish *s, uint8_t *out, size_t n);
void sfsim_cb_pop(struct sim_sailfish *s, size_t n);
size_t sfsim_planner_used(struct sim_sailfish *s, double now);
void sfsim_commands(struct sim_sailfish *s, double now);
void sfsim_physics(struct sim_sailfish *s, double dt);

#endif
