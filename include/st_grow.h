/*
 * st_grow.h - the one growth rule for dynamic arrays, header-only like
 * st_error.h so every module may use it: double the capacity, starting at
 * 16, with overflow checks.  (slicer/grow.h wraps it.)
 */
#ifndef STRATUM_ST_GROW_H
#define STRATUM_ST_GROW_H

#include <stdint.h>
#include <stdlib.h>

#include "st_error.h"

/*
 * st_grow - arr (capacity *cap elements of elem bytes) reallocated to hold
 * at least need elements.  Returns the new array and updates *cap, or NULL
 * (arr and *cap untouched, arr still owned by the caller) when out of
 * memory or the size would overflow.
 */
static inline void *st_grow(void *arr, size_t *cap, size_t need, size_t elem)
{
	size_t ncap = *cap ? *cap : 16;
	void *grown;

	if (need <= *cap)
		return arr;
	while (ncap < need) {
		if (ncap > SIZE_MAX / 2)
			return NULL;
		ncap *= 2;
	}
	if (ncap > SIZE_MAX / elem || !(grown = realloc(arr, ncap * elem)))
		return NULL;
	*cap = ncap;
	return grown;
}

/*
 * st_grow_at - st_grow through a pointer to the array: *arr is replaced by
 * the grown array.  Returns 0, or ST_ERR_NOMEM with *arr and *cap kept.
 */
static inline int st_grow_at(void **arr, size_t *cap, size_t need, size_t elem)
{
	void *p = st_grow(*arr, cap, need, elem);

	if (!p)
		return ST_ERR_NOMEM;
	*arr = p;
	return 0;
}

#endif /* STRATUM_ST_GROW_H */
