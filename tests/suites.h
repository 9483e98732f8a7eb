/*
 * suites.h - one Check suite per module; check_main.c runs them (all, or a
 * lane of them: tests/lanes.sh), and `make check` ends with one summary line.
 */
#ifndef STRATUM_TESTS_SUITES_H
#define STRATUM_TESTS_SUITES_H

#include <check.h>

Suite *stfile_suite(void);	/* tests/check_stfile.c: the atomic file writer of include/ */
Suite *mesh_suite(void);	/* tests/check_mesh.c: welding, topology report */
Suite *meshio_suite(void);	/* tests/check_meshio.c: STL/OBJ/OFF I/O, bad input */
void meshio_bad_tcases(Suite *s); /* tests/check_meshio_bad.c: bad input, writer failures, part of meshio */
void meshio_3mf_tcases(Suite *s); /* tests/check_meshio_3mf.c: 3MF, part of the meshio suite */
Suite *exact_suite(void);	/* tests/check_exact.c: CGAL bridge predicates */
void exact_pairs_tcases(Suite *s); /* tests/check_exact_pairs.c: hand-placed pairs, arguments, part of exact */
void exact_patches_tcases(Suite *s); /* tests/check_patches.c: flat patches of the count, part of exact */
Suite *repair_suite(void);	/* tests/check_repair.c: seed 000 repair end to end */
void repair_sheet_tcases(Suite *s); /* tests/check_repair_sheet.c: sheets, wires, soups, part of repair */
Suite *planar_suite(void);	/* tests/check_planar.c: planar simplification of flat faces */
Suite *thicken_suite(void);	/* tests/check_thicken.c: sheets into closed slabs */
Suite *heal_suite(void);	/* tests/check_heal.c: welding, stitching, hole filling */
Suite *batch_suite(void);	/* tests/check_batch.c: independent groups repaired apart */
Suite *corpus_suite(void);	/* tests/check_corpus.c: repair on generated defect cases */
Suite *profile_suite(void);	/* tests/check_profile.c: printer profiles */
void profile_cli_tcases(Suite *s); /* tests/check_profile_cli.c: access, lookup, stratum printers, part of profile */
void profile_find_tcases(Suite *s); /* tests/check_profile_find.c: --printer lookup, part of profile */
void profile_shipped_tcases(Suite *s); /* tests/check_profile_shipped.c: every shipped printers/NAME.ini slices, part of profile */
Suite *ini_suite(void);		/* tests/check_ini.c: the ini reader of profiles and the node config */
Suite *placeholder_suite(void); /* tests/check_placeholder.c: PrusaSlicer's placeholder language */
Suite *gcode_suite(void);	/* tests/check_gcode.c: G-code parser and reader */
void gcode_errors_tcases(Suite *s); /* tests/check_gcode_errors.c: refusals, classifier, part of gcode */
void gcode_io_tcases(Suite *s); /* tests/check_gcode_io.c: the streaming reader, robustness, part of gcode */
Suite *xport_suite(void);	/* tests/check_xport.c: serial transports (pty, TCP) */
Suite *sim_suite(void);		/* tests/check_sim.c: simulated Marlin over a pty */
void sim_faults_tcases(Suite *s); /* tests/check_sim_faults.c: faults, printcore, part of sim */
Suite *marlin_suite(void);	/* tests/check_marlin.c: Marlin driver against the simulator */
void marlin_faults_tcases(Suite *s); /* tests/check_marlin_faults.c: hangs, lost replies, stops, part of marlin */
void marlin_parse_tcases(Suite *s); /* tests/check_marlin_parse.c: reply parsing, part of marlin */
Suite *printer_suite(void);	/* tests/check_printer.c: printer.h adapters on both simulators */
Suite *slicer_suite(void);	/* tests/check_slicer.c: slicing, Clipper bridge, walls */
void slicer_modes_tcases(Suite *s); /* tests/check_modes.c: spiral vase, part of slicer */
void slicer_travel_tcases(Suite *s); /* tests/check_travel.c: travel and retraction, part of slicer */
void slicer_clip_tcases(Suite *s); /* tests/check_clip_kept.c: clip_erosion_kept, part of slicer */
Suite *gcodewriter_suite(void); /* tests/check_gcodewriter.c: G-code writer and estimator */
void gcodewriter_cooling_tcases(Suite *s); /* tests/check_gcodewriter_cooling.c: fan, slow-down, planner, part of gcodewriter */
void gcodewriter_simplify_tcases(Suite *s); /* tests/check_simplify.c: gcode_resolution, part of gcodewriter */
/* tests/check_simplify.c, shared with check_arcfit.c: a stack of round walls, waves and a thin
 * wall; the writer's output for it with s equal to a golden file; a sliced 256-sided cylinder */
struct layer_stack *dense_stack(void);
struct gcodew_settings;
void dense_stack_matches(const struct gcodew_settings *s, const char *golden);
char *slice_cylinder_for(double h, const char *printer, const char *args, char *out, size_t cap);
/* tests/check_arcfit.c: arc_fitting, part of gcodewriter */
void gcodewriter_arcfit_tcases(Suite *s);
void gcodewriter_retract_tcases(Suite *s); /* tests/check_retract.c: retract_layer_change, lift range, part of gcodewriter */
void gcodewriter_accel_tcases(Suite *s); /* tests/check_accel.c: accelerations per role, part of gcodewriter */
void gcodewriter_progress_tcases(Suite *s); /* tests/check_progress.c: remaining_times, part of gcodewriter */
Suite *infill_suite(void);	/* tests/check_infill.c: skins, bridges, infill */
void infill_solid_tests(TCase *tc); /* tests/check_infill_solid.c: shells, strips, gyroid, in infill's "infill" */
void infill_shell_tcases(Suite *s); /* tests/check_shells.c: vertical shells, part of infill */
Suite *support_suite(void);	/* tests/check_support.c: skirt, brim, support material */
Suite *supportmodel_suite(void); /* tests/check_support_model.c: support on the model, bridges, verified */
Suite *raft_suite(void);	/* tests/check_raft.c: the raft under the part */
Suite *adaptive_suite(void);	/* tests/check_adaptive.c: adaptive layer heights */
void adaptive_3mf_tcases(Suite *s); /* tests/check_adaptive_3mf.c: a 3MF's layer height profile */
Suite *multimodel_suite(void); /* tests/check_multimodel.c: several models in one slice */
Suite *slicecli_suite(void);	/* tests/check_slicecli.c: stratum slice end to end */
void slicecli_config_tests(TCase *tc); /* tests/check_slicecli_config.c: PrusaSlicer configs, in slicecli's "slice" */
void slicecli_settings_tcases(Suite *s); /* tests/check_slicesettings.c: settings honoured, part of slicecli */
void slicecli_settings_more_tests(TCase *tc); /* tests/check_slicesettings_more.c: in slicecli's "settings" */
void slicecli_widths_tcases(Suite *s); /* tests/check_slicewidths.c: per-role widths, part of slicecli */
void slicecli_thumbnail_tcases(Suite *s); /* tests/check_thumbnail.c: G-code thumbnails, part of slicecli */
Suite *region_suite(void);	/* tests/check_region.c: printed region against cross-sections */
Suite *thin_suite(void);	/* tests/check_thin.c: walls thinner than the nozzle */
Suite *x3g_suite(void);		/* tests/check_x3g.c: G-code to X3G, decoder, against gpx */
void x3g_gpx_tcases(Suite *s); /* tests/check_x3g_gpx.c: the decoder, against gpx, part of x3g */
Suite *s3g_suite(void);		/* tests/check_s3g.c: S3G packets, driver, simulated Sailfish */
void s3g_packets_tcases(Suite *s); /* tests/check_s3g_packets.c: CRC, framing, tables, part of s3g */
Suite *serve_suite(void);		/* tests/check_serve.c: stratum serve, the farm node's API and queue */
void serve_mqtt_tcases(Suite *s); /* tests/check_servemqtt.c: the node on a shared broker, part of serve */
void serve_mqtt_name_tests(TCase *tc); /* tests/check_servemqtt_name.c: one node per name, in serve's "mqtt" */
Suite *octoapi_suite(void);	/* tests/check_octoapi.c: the node's OctoPrint calls, one test each */
void octoapi_printer_tests(TCase *tc); /* tests/check_octoapi_printer.c: printer and job calls, in octoapi's "calls" */
void octoapi_push_tcases(Suite *s); /* tests/check_octopush.c: the push API, part of octoapi */
void serve_abuse_tcases(Suite *s); /* tests/check_serveabuse.c: the node bounded under abuse, part of serve */
void serve_sim_tcases(Suite *s);   /* tests/check_servesim.c: the node with simulated printers and MQTT, part of serve */
void serve_page_tcases(Suite *s);   /* tests/check_servepage.c: the status page in Chromium, part of serve */
Suite *farm_suite(void);	/* tests/check_farm.c: stratum farm, the farm view over two nodes */
void octoapi_queue_tcases(Suite *s); /* tests/check_octoqueue.c: job calls and the queue, part of octoapi */
void octoapi_inject_tcases(Suite *s); /* tests/check_octoinject.c: commands inside a print, part of octoapi */
Suite *preview_suite(void);	/* tests/check_preview.c: layer preview, move walker */
Suite *portpick_suite(void);	/* tests/check_portpick.c: --port auto on fake enumerations */
Suite *send_suite(void);	/* tests/check_send.c: stratum send to the simulated Sailfish */
Suite *console_suite(void);	/* tests/check_console.c: stratum console, send --command */
Suite *guard_suite(void);	/* tests/check_guard.c: the wrong-printer guard, send/print/x3g */
Suite *print_suite(void);	/* tests/check_print.c: stratum print end to end, both simulators */
Suite *cli_suite(void);		/* tests/check_cli.c: the stratum binary end to end */
void cli_repair_tcases(Suite *s); /* tests/check_cli_repair.c: stratum repair end to end, part of cli */
void cli_stdio_tcases(Suite *s); /* tests/check_clio.c: "-" for stdin/stdout, print --json, part of cli */
Suite *jobs_suite(void);	/* tests/check_jobs.c: stratum jobs list/show/prune, the size cap */
Suite *help_suite(void);	/* tests/check_help.c: --help, man pages, completion = the option tables */
Suite *progress_suite(void);	/* tests/check_hostprogress.c: progress lines, ETA, printer clock */
Suite *install_suite(void);	/* tests/check_install.c: make install into a DESTDIR, run from there */
Suite *analyze_suite(void);	/* tests/check_analyze.c: cusp height (seed 004), stratum analyze */
Suite *compare_suite(void);	/* tests/check_compare.c: surface deviation, chordal error, stratum compare */
Suite *refine_suite(void);	/* tests/check_refine.c: vertex translation (seed 003), stratum refine */

#endif
