/*
 * grow.h - the one growth rule for the slicer's dynamic arrays (private to
 * slicer/): double the capacity, starting at 16, with overflow checks.
 */
#ifndef STRATUM_SLICER_GROW_H
#define STRATUM_SLICER_GROW_H

#include "st_grow.h"

/*
 * slice_grow - arr (capacity *cap elements of elem bytes) reallocated to
 * hold at least need elements.  Returns the new array and updates *cap, or
 * NULL (arr and *cap untouched, arr still owned by the caller) when out of
 * memory or the size would overflow.
 */
static inline void *slice_grow(void *arr, size_t *cap, size_t need, size_t elem)
{
	return st_grow(arr, cap, need, elem);
}

#endif /* STRATUM_SLICER_GROW_H */
