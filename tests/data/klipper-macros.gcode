; Start G-code of PrusaSlicer's Klipper printers (Voron, RatRig), Infinity3D's
; text line, Jubilee's T-1 (RepRapFirmware: deselect the tool) and a bare T:
; lines that are not G, M or T commands.
; Marlin answers each with echo:Unknown command, Klipper runs it; see
; docs/errors.md "G-code input".
M107
print_start EXTRUDER=240 BED=110 CHAMBER=0
START_PRINT EXTRUDER_TEMP=215 BED_TEMP=60
BED_MESH_CALIBRATE ; probe the bed
SET_PRESSURE_ADVANCE ADVANCE=0.05
SET_GCODE_OFFSET Z=0.02
Start printing
T-1 ; Make sure nothing is parked on the carriage
T
TURN_OFF_HEATERS
G28
G1 X10 Y10 F3000
END_PRINT
