; Lines that Marlin (and Prusa's firmware) accept, from users' custom G-code
; and PrusaSlicer's bundled start G-code; see docs/errors.md "G-code input".
M115 U3.11.0 ; tell printer latest fw version
M862.3 P "MK3S" ; printer model check
M862.1 P0.4 ; nozzle diameter check
M862.5 P2 ; g-code level check
M73 P0 R37
M73 Q0 S37
M117 Bed: 60°C
M117 Wärmen … ok
M118 E1 Hello "host"
M0 Click to continue
M1 Change filament
M0 S1 Remove the print (then press)
G28 W ; home all without mesh bed level
G80 ; mesh bed leveling
G29
M900 K0.05 ; Filament gcode LA 1.5
G1	X10	Y10 F3000 ; tabs between words
M999 Q1 W ; unknown to the firmware: "Unknown command", then ok
G28 X0 Y0 Q ; unknown letter
; Prusa MMU
T?
Tx
Tc
M117 Done