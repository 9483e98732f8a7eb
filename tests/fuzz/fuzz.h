/*
 * fuzz.h - shared by the libFuzzer targets in tests/fuzz/ (make fuzz,
 * docs/reliability.md): a transport whose "printer" says exactly the fuzzer's
 * bytes, so the Marlin and S3G drivers run their real code on them.
 */
#ifndef STRATUM_TESTS_FUZZ_H
#define STRATUM_TESTS_FUZZ_H

#include <stddef.h>
#include <stdint.h>

#include "xport.h"

/*
 * fuzz_xport_new - a transport whose printer says (data, len) in turns:
 * the bytes up to ends[0] are there at once (a boot banner), and each write
 * makes the next turn, up to ends[i], readable, as a printer answers what it
 * was sent.  Between turns a read finds nothing (the caller polls and waits
 * as on a real port, but on the transport's simulated clock, which jumps
 * to the end of a wait that would block: no real time passes); after the
 * last byte the other end is gone, so every run ends.  ends[nturns - 1] must be len; turns may be empty (no answer).
 * data and ends are copied; writes are dropped.  Close with xport_close.
 * NULL when out of memory or the pipe it polls on cannot be made.
 */
struct xport *fuzz_xport_new(const uint8_t *data, size_t len, const size_t *ends,
			     size_t nturns);

/* fuzz_tmpdir - a private folder for this process, removed at exit: in
 * $TMPDIR, else /dev/shm (memory), else /tmp. */
const char *fuzz_tmpdir(void);

#endif /* STRATUM_TESTS_FUZZ_H */
