#!/usr/bin/env bash
# Regenerates every file in renders/ (videos, stills, plots) from the models in models/.
# Run from the top of the repository after building: bash renders/make_gallery.sh
# (MJTETHER=path/to/mjtether to use another build). Takes about 10 minutes on 2 cores.
set -euo pipefail
M=${MJTETHER:-./build/mjtether}
R=renders
# Stills directories are remade, so that no still of an older run stays behind.
find "$R" -mindepth 1 -maxdepth 1 -type d -exec rm -rf {} +

# Default scene: the ROV drives down-current on its thrusters until the tether snaps taut.
$M render models/rov_tether.xml --duration 20 --fps 15 --size 640x360 \
  --video $R/rov_tether.mp4 --png-every 5 $R/rov_tether
$M render models/rov_tether.xml --duration 9.6 --fps 10 --size 1280x720 \
  --png-every 9.5 $R/rov_tether_hd
$M plot models/rov_tether.xml --duration 20 --out $R/rov_tether_plot.png

# BlueROV2 Heavy manoeuvres on a 30 m tether from a fixed surface point.
$M render models/manoeuvre_surge_snap.xml --duration 24 --fps 15 --size 640x360 \
  --video $R/manoeuvre_surge_snap.mp4 --png-every 8 $R/manoeuvre_surge_snap
$M plot models/manoeuvre_surge_snap.xml --duration 24 --out $R/manoeuvre_surge_snap_plot.png

$M render models/manoeuvre_dive_return.xml --duration 30 --fps 10 --speedup 1.5 \
  --size 640x360 --video $R/manoeuvre_dive_return.mp4 --png-every 10 $R/manoeuvre_dive_return
$M plot models/manoeuvre_dive_return.xml --duration 30 --out $R/manoeuvre_dive_return_plot.png

$M render models/manoeuvre_station_keeping.xml --duration 40 --fps 7.5 --speedup 2 \
  --size 640x360 --video $R/manoeuvre_station_keeping.mp4 \
  --png-every 20 $R/manoeuvre_station_keeping
$M plot models/manoeuvre_station_keeping.xml --duration 40 \
  --out $R/manoeuvre_station_keeping_plot.png

$M render models/manoeuvre_turn_wrap.xml --duration 30 --fps 10 --speedup 1.5 \
  --size 640x360 --video $R/manoeuvre_turn_wrap.mp4 --png-every 10 $R/manoeuvre_turn_wrap
$M plot models/manoeuvre_turn_wrap.xml --duration 30 --out $R/manoeuvre_turn_wrap_plot.png
# The same turn from close by: the camera looks at the vehicle.
$M render models/manoeuvre_turn_wrap.xml --duration 30 --fps 10 --speedup 1.5 --size 640x360 \
  --camera track:rov --video $R/manoeuvre_turn_wrap_closeup.mp4 \
  --png-every 15 $R/manoeuvre_turn_wrap_closeup

# A tether dragged over a rock (an hfield geom named in contact=, docs/contact.md): small, 20 s.
$M render models/hfield_rock.xml --duration 20 --fps 10 --size 480x270 \
  --video $R/hfield_rock.mp4 --png-every 10 $R/hfield_rock
$M plot models/hfield_rock.xml --duration 20 --out $R/hfield_rock_plot.png

# BlueROV2 Heavy hanging from a heaving boat.
$M render models/bluerov2_heavy.xml --duration 20 --fps 10 --size 640x360 \
  --video $R/bluerov2_heavy.mp4 --png-every 10 $R/bluerov2_heavy
$M plot models/bluerov2_heavy.xml --duration 20 --out $R/bluerov2_heavy_plot.png

# Work-class ROV on 100 m from a TMS: a 300 s run as a 20 s time-lapse.
$M render models/workclass_rov_tms.xml --duration 300 --fps 1 --speedup 15 --size 640x360 \
  --video $R/workclass_rov_tms.mp4 --png-every 100 $R/workclass_rov_tms
$M plot models/workclass_rov_tms.xml --duration 300 --every 0.5 \
  --out $R/workclass_rov_tms_plot.png

# Work-class ROV leaving its TMS with a constant-tension winch (docs/winch.md): 200 s as a
# 20 s time-lapse; the plot (tensions, deployed length, payout speed, depth) from the run's log.
$M render models/workclass_rov_tms_winch.xml --duration 200 --fps 1 --speedup 10 --size 640x360 \
  --video $R/workclass_rov_tms_winch.mp4 --png-every 50 $R/workclass_rov_tms_winch
$M run models/workclass_rov_tms_winch.xml --duration 200 --log $R/workclass_rov_tms_winch.csv
$M plot $R/workclass_rov_tms_winch.csv --out $R/workclass_rov_tms_winch_plot.png
rm $R/workclass_rov_tms_winch.csv
