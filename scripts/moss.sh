#!/usr/bin/env bash
# The MOSS figures of thesis sec. 5.5 (apps/moss/README.md): one command per
# figure pair, resumable (rerun the same command after an interruption).
#
#   scripts/moss.sh corridor   # figs. 5.6 / 5.7: C = 1..20, 10 + 10 trials
#   scripts/moss.sh square     # figs. 5.9 / 5.10: C = 6, 11, 16, 21, 100 + 20 trials
#   scripts/moss.sh intel|aces|freiburg-079 # the same on a real CARMEN log (DATA: ../shared/data/carmen)
#
# On a log the trials' odometry is the log's ODOM records; ODOMETRY=synthetic
# (the reference motion plus simulated noise, an ablation) goes into its own
# folder (suffix _synthetic); POSES sets the trial length (folder _N<poses>).
# Matches are gated against dead reckoning (GATE, a chi-square; 0: none,
# suffix _gate0) and their information calibrated on the training trials
# (CALIBRATE=0: not, suffix _uncalibrated): apps/moss/REAL_LOGS.md.
#
# T and K default to the thesis' 10 and 1000; STEPS=200 scripts/moss.sh square
# runs a reduced K (into its own folder, since a folder holds one setting).
# OUT (results/moss), BUILD (build) and THREADS (the cores) may be set too;
# INFORMATION=censi uses Censi's closed-form ICP covariance for the L2G
# factors (into its own folder, suffix _censi); CENSI_SIGMA=0.05 sets the
# sigma_d it assumes (default 0: the laser's 2 cm; folder suffix _censi0.05).
# OBJECTIVE=sum_of_norms makes MOSS minimise eq. 5.3's sum of error norms
# instead of the RMSE (folder suffix _sum_of_norms); both are reported.
set -euo pipefail
cd "$(dirname "$0")/.."
BUILD=${BUILD:-build}
OUT=${OUT:-results/moss}
CLIMBS=${CLIMBS:-10}
STEPS=${STEPS:-1000}
THREADS=${THREADS:-0}
INFORMATION=${INFORMATION:-hessian}
CENSI_SIGMA=${CENSI_SIGMA:-0}
OBJECTIVE=${OBJECTIVE:-rmse}
ODOMETRY=${ODOMETRY:-log}
SUFFIX=""""
[ "$INFORMATION" = hessian ] || SUFFIX="_$INFORMATION"
[ "$INFORMATION" = censi ] && [ "$CENSI_SIGMA" != 0 ] && SUFFIX="${SUFFIX}${CENSI_SIGMA}"
[ "$OBJECTIVE" = rmse ] || SUFFIX="${SUFFIX}_$OBJECTIVE"
PY=/usr/bin/python3
[ -x "$PY" ] || PY=python3
case "${1:-}" in
  corridor)
    dir="$OUT/corridor_T${CLIMBS}_K${STEPS}${SUFFIX}"
    nice -n 10 "$BUILD/apps/hamal_moss" experiment --world corridor --sizes 1-20 --train 10 \
      --test 10 --climbs "$CLIMBS" --steps "$STEPS" --threads "$THREADS" \
      --information "$INFORMATION" --censi_sigma "$CENSI_SIGMA" --objective "$OBJECTIVE" --output "$dir"
    "$PY" apps/moss/moss_report.py "$dir" --nodes_sizes 1,2,3,4 ;;
  square)
    dir="$OUT/square_T${CLIMBS}_K${STEPS}${SUFFIX}"
    nice -n 10 "$BUILD/apps/hamal_moss" experiment --world square --sizes 6,11,16,21 \
      --train "${SQUARE_TRAIN:-100}" --test 20 --climbs "$CLIMBS" --steps "$STEPS" \
      --threads "$THREADS" --information "$INFORMATION" --censi_sigma "$CENSI_SIGMA" --objective "$OBJECTIVE" --output "$dir"
    "$PY" apps/moss/moss_report.py "$dir" --nodes_sizes 6,11,16,21 ;;
  intel|aces|freiburg-079)
    # One cut for every log (apps/moss/REAL_LOGS.md): the first
    # visits map, trials of POSES poses revisit them.
    poses=${POSES:-3}
    [ "$ODOMETRY" = log ] || SUFFIX="${SUFFIX}_$ODOMETRY"
    gate=${GATE:-11.34}
    [ "$gate" = 11.34 ] || SUFFIX="${SUFFIX}_gate$gate"
    calibrate=true
    [ "${CALIBRATE:-1}" = 0 ] && calibrate=false && SUFFIX="${SUFFIX}_uncalibrated"
    dir="$OUT/${1}_T${CLIMBS}_K${STEPS}_N${poses}${SUFFIX}"
    nice -n 10 "$BUILD/apps/hamal_moss" experiment --data "${DATA:-../shared/data/carmen}/$1.log" \
      --poses "$poses" --odometry "$ODOMETRY" \
      --l2g_gate "$gate" --calibrate_information="$calibrate" \
      --sizes 2,5,10,15,20,30 --climbs "$CLIMBS" --steps "$STEPS" \
      --threads "$THREADS" --information "$INFORMATION" --censi_sigma "$CENSI_SIGMA" --objective "$OBJECTIVE" --output "$dir"
    "$PY" apps/moss/moss_report.py "$dir" --nodes_sizes 5,10,20 ;;
  *)
    echo "usage: scripts/moss.sh corridor|square|intel|aces|freiburg-079" >&2
    exit 2 ;;
esac
