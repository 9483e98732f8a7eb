/*
 * output.h - private to repair/: the last step of repair_mesh, after
 * rounding.  repair.c is the only user.
 */
#ifndef STRATUM_REPAIR_OUTPUT_H
#define STRATUM_REPAIR_OUTPUT_H

#include <stdbool.h>
#include <stdint.h>

#include "mesh.h"
#include "repair.h"
#include "st_error.h"

/*
 * repair_result_printable - whether a checked result may be written:
 * printable as `stratum check` judges it (several parts and cavities
 * allowed, docs/check.md) and free of the warnings a repair must not
 * leave behind (duplicates, inside out, inconsistent orientation).
 */
bool repair_result_printable(const struct mesh_report *mr);

/*
 * repair_finish_parts - check *m (known: its self-intersection count when
 * already known, else -1), drop the parts smaller than opt->epsilon in
 * every direction (a nozzle that wide cannot draw them; counted in rep),
 * number the parts into *component (when non-NULL; a part is a solid with
 * its cavities) and fill the output half of rep.  *m may be replaced by a
 * new mesh.  Returns 0 or a negative class with err filled.
 *
 * batch (NULL, or per triangle of *m the batch it was repaired in,
 * repair/batch.h): *apart receives whether the batches' results are
 * independent as their repairs assumed, that is no shell of one lies in
 * a shell of another (then a part would hold two batches' triangles, or
 * be misnested, or sit in another part's cavity, where repairing the
 * whole would have deleted it).  When not apart nothing else is done.
 */
int repair_finish_parts(struct mesh **m, const struct repair_options *opt, long long known,
			const uint32_t *batch, bool *apart, uint32_t **component,
			struct repair_report *rep, struct st_error *err);

#endif /* STRATUM_REPAIR_OUTPUT_H */
