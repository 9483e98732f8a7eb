/*
 * exacttest.h - what the exact suite's files share (check_exact.c,
 * check_exact_pairs.c).
 */
#ifndef STRATUM_TESTS_EXACTTEST_H
#define STRATUM_TESTS_EXACTTEST_H

#include <stdint.h>

/*
 * ISO C before C23 does not convert double (*)[3] to const double (*)[3]
 * implicitly, so callers with writable tables cast.
 */
#define CVERTS(v) ((const double(*)[3])(v))
#define CTRIS(t) ((const uint32_t(*)[3])(t))

#endif
