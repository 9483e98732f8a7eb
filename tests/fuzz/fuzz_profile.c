/*
 * fuzz_profile.c - the printer profile loader (host/profile.h) on arbitrary
 * text, then what a loaded profile feeds: the slicer settings
 * (profile_slicer_config, slicer_config_check), the X3G machine and the
 * JSON and INI writers.
 */
#include <stddef.h>
#include <stdint.h>
#include <stdio.h>

#include <jansson.h>

#include "profile_x3g.h"
#include "profile.h"
#include "profile_slicer.h"
#include "slicer.h"
#include "x3g.h"

int LLVMFuzzerTestOneInput(const uint8_t *data, size_t size);

int LLVMFuzzerTestOneInput(const uint8_t *data, size_t size)
{
	struct st_error err = {0};
	struct profile *p = NULL;

	if (profile_load_buffer((const char *)data, size, "fuzz.ini", &p, &err))
		return 0;
	{
		struct slicer_config c;

		if (!profile_slicer_config(p, &c, &err))
			(void)slicer_config_check(&c, &err);
	}
	{
		struct x3g_machine m;
		enum x3g_flavor flavor;

		(void)profile_x3g_machine(p, &m, &flavor, &err);
	}
	json_decref(profile_to_json(p));
	{
		FILE *f = fopen("/dev/null", "w");

		if (f) {
			(void)profile_write(p, f);
			fclose(f);
		}
	}
	profile_free(p);
	return 0;
}
