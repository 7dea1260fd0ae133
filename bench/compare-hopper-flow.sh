#!/usr/bin/env bash
# grainflow against LIGGGHTS 3.8 on the hopper of bench/liggghts-mesh, filled by insertion and
# discharged (issue #29), in the same session, filling included: both codes from an empty
# hopper, the same 9 976-triangle mesh (the peer's make_geometry.py, checked against its
# checksums), the same spheres, contact law, time step and number of steps. LIGGGHTS runs the
# peer's own inputs: in.hopper_fill.liggghts (NINSERT steps of insert/rate/region, 2 350 spheres
# every 2 000 steps up to 30 000, the orifice closed by the plane z = 0; NSETTLE steps settling;
# the state written) then in.hopper_discharge.liggghts (that state, the lid gone, NDISCHARGE
# steps; spheres leaving the box are deleted). grainflow runs bench/cases/hopper_flow.toml, one
# run of the same NINSERT + NSETTLE + NDISCHARGE steps: the same insertion, the orifice closed
# by a two-triangle lid that drops out of the box when the discharge starts, `leaving =
# "remove"`.
#
# Speed: particle-steps per second, each code's own count of its spheres summed over the steps
# (sampled every 100 steps, every 2 000 in LIGGGHTS's fill; a sample counts for the steps since
# the one before) ÷ its wall time: LIGGGHTS's loop times ("Loop time", the fill's two runs and
# the discharge's; reading and writing the state not counted), grainflow's `wall time`. Also
# with the full count (30 000 × steps) for both. LIGGGHTS on one core (OMP_NUM_THREADS=1),
# grainflow on 1 thread (-j 1), median of RUNS rounds in which each code runs once, in turn,
# grainflow ÷ LIGGGHTS (also round by round), and each code's spheres at the end (they
# discharged as fast: a check of the physics, not a match).
#
# Differences left: LIGGGHTS zeroes the velocities and loses the contact histories between its
# two inputs (the state goes through a data file); its lid is an infinite plane, grainflow's a
# 16 mm square (beads touch the lid only at the orifice). grainflow's time series has a row
# every 100 steps (its counts), LIGGGHTS's discharge a thermo row every 100.
#
# Results go on top of bench/results/<date>-hopper-flow.md (the day's earlier runs stay below).
#
#   bench/compare-hopper-flow.sh       (RUNS=3; NINSERT=26000 NSETTLE=4000 NDISCHARGE=20000;
#                                       CARGO= the cargo command; MP= the LIGGGHTS mesh inputs, default bench/liggghts-mesh)
set -euo pipefail
# One block, read whole before it runs (an edit of this file during a run changes nothing).
{
cd "$(dirname "$0")/.."
ROOT=$PWD
MP=${MP:-$ROOT/bench/liggghts-mesh}
RUNS=${RUNS:-3}
NINSERT=${NINSERT:-26000}
NSETTLE=${NSETTLE:-4000}
NDISCHARGE=${NDISCHARGE:-20000}
CARGO=${CARGO:-cargo}
DT=2e-5
BEAD=1.0471975511965977e-5      # kg: 2500 × π/6 × (2 mm)³
mkdir -p bench/results
if ! command -v liggghts >/dev/null; then
  apt-get update -qq && apt-get install -y -qq --no-install-recommends liggghts >/dev/null
fi
$CARGO build --release --quiet
GF=$ROOT/target/release/grainflow
W=$(mktemp -d)
trap 'rm -rf "$W"' EXIT

# Geometry: the STLs as the peer generates them; grainflow's lid, a 16 mm square at z = 0
# facing up.
mkdir -p "$W/data"
python3 "$MP/make_geometry.py" "$W/data" >/dev/null
(cd "$W/data" && sha256sum --quiet -c "$MP/stl.sha256") || echo "warning: the STL files differ from $MP/stl.sha256" >&2
cat > "$W/data/hopper_flow_lid.obj" <<'OBJ'
# lid under the 12 mm orifice: 16 mm square at z = 0, normal +z
v -0.008 -0.008 0
v 0.008 -0.008 0
v 0.008 0.008 0
v -0.008 0.008 0
f 1 2 3
f 1 3 4
OBJ
cd "$W"

# The steps and LIGGGHTS's batches within NINSERT (at steps 1, 2 001, …), for grainflow's count.
n=$((NINSERT + NSETTLE + NDISCHARGE))
batches=$(( (NINSERT - 1) / 2000 + 1 ))
count=$(( batches * 2350 < 30000 ? batches * 2350 : 30000 ))
t_open=$(python3 -c "print(($NINSERT + $NSETTLE) * $DT)")
sed "s|^t_stop = .*|t_stop = $(python3 -c "print(($n - 0.5) * $DT)")|
     s|^start = .*|start = $t_open|
     s|^stop = .*|stop = $(python3 -c "print($t_open + 0.02)")|
     s|^count = .*|count = $count|" "$ROOT/bench/cases/hopper_flow.toml" > hopper_flow.toml

median() { sort -g | awk '{a[NR]=$1} END {print (NR%2) ? a[(NR+1)/2] : (a[NR/2]+a[NR/2+1])/2}'; }
range() { sort -g | awk 'NR==1{lo=$1} {hi=$1} END {printf "%.2f–%.2f", lo, hi}'; }
# LIGGGHTS's logs: the loop times summed; the spheres summed over the steps, from each thermo
# block's rows (found by its header's Step and Atoms); the spheres at the end.
lig_loop() { cat "$@" | awk '/^Loop time of/{t+=$4} END {print t}'; }
lig_psteps() {
  cat "$@" | awk '/^ *Step /{f=1; prev=""; for(j=1;j<=NF;j++) {if($j=="Step") cs=j; if($j=="Atoms") ca=j}; next}
                  /^Loop time/{f=0}
                  f && $1 ~ /^[0-9]+$/ {if (prev != "") s+=$ca*($cs-prev); prev=$cs}
                  END {printf "%.0f\n", s}'
}
lig_atoms() { awk '/^Loop time of/{for(k=1;k<=NF;k++) if($k=="with") a=$(k+1)} END {print a}' "$1"; }
# grainflow's run: its wall time; its spheres (mass ÷ one sphere's) summed over the steps from
# the time series' rows; the spheres at the end.
gf_wall() { awk '/^wall time/{print $3}' "$1"; }
gf_psteps() {
  awk -F, -v m=$BEAD 'NR==1{for(j=1;j<=NF;j++) {if($j=="step") cs=j; if($j=="mass") cm=j}; next}
                      {if (NR > 2) s+=int($cm/m+0.5)*($cs-prev); prev=$cs} END {printf "%.0f\n", s}' "$1"
}
gf_atoms() { awk -F, -v m=$BEAD 'NR==1{for(j=1;j<=NF;j++) if($j=="mass") cm=j; next} {a=int($cm/m+0.5)} END {print a}' "$1"; }

rm -f lig.speeds gf.speeds lig.full gf.full rounds.md
for i in $(seq "$RUNS"); do
  OMP_NUM_THREADS=1 liggghts -in "$MP/in.hopper_fill.liggghts" -var mesh 10k -var mdir data -var idir "$MP" \
    -var ninsert "$NINSERT" -var nsettle "$NSETTLE" -var out lig.fill.t$i.data -log lig.fill.t$i > lig.fill.t$i.screen 2>&1
  OMP_NUM_THREADS=1 liggghts -in "$MP/in.hopper_discharge.liggghts" -var mesh 10k -var mdir data -var idir "$MP" \
    -var data lig.fill.t$i.data -var nwarm 0 -var nrun "$NDISCHARGE" -var nthermo 100 -log lig.dis.t$i > lig.dis.t$i.screen 2>&1
  rm -f lig.fill.t$i.data
  lt=$(lig_loop lig.fill.t$i lig.dis.t$i)
  python3 -c "print($(lig_psteps lig.fill.t$i lig.dis.t$i) / $lt / 1e6)" >> lig.speeds
  python3 -c "print(30000 * $n / $lt / 1e6)" >> lig.full
  $GF run hopper_flow.toml -j 1 -q --out gf.t$i > gf.t$i.log
  gt=$(gf_wall gf.t$i.log)
  python3 -c "print($(gf_psteps gf.t$i/timeseries.csv) / $gt / 1e6)" >> gf.speeds
  python3 -c "print(30000 * $n / $gt / 1e6)" >> gf.full
done
sl=$(median < lig.speeds); sg=$(median < gf.speeds)
fl=$(median < lig.full); fg=$(median < gf.full)
out="$ROOT/bench/results/$(date +%Y-%m-%d)-hopper-flow.md"
new="$W/section.md"
{
  echo "# grainflow vs LIGGGHTS, hopper filled by insertion and discharged, $(date -u +%Y-%m-%dT%H:%MZ)"
  echo
  echo "Machine: $(lscpu | awk -F: '/Model name/{gsub(/^ +/,"",$2); print $2}'), $(nproc) cores, $(free -g | awk '/Mem/{print $2}') GiB;"
  echo "$(liggghts -h 2>/dev/null | sed -n 's/.*(Version \(.*\), compiled.*/\1/p' | head -1) on one core (OMP_NUM_THREADS=1); grainflow $($GF --version | awk '{print $2}') (-j 1), git $(git -C "$ROOT" rev-parse --short HEAD)."
  echo "9 976-triangle hopper; $NINSERT steps inserting ($count spheres), $NSETTLE settling, $NDISCHARGE discharging ($n in all, dt = $DT s)."
  echo "Millions of particle-steps per second, median (range) of $RUNS rounds in which each code ran once, in turn."
  echo
  echo "| | LIGGGHTS | grainflow | grainflow ÷ LIGGGHTS |"
  echo "|---|---|---|---|"
  python3 -c "print(f'| particle-steps/s, spheres present | {$sl:.2f} ($(range < lig.speeds)) | {$sg:.2f} ($(range < gf.speeds)) | {$sg / $sl:.2f} |')"
  python3 -c "print(f'| particle-steps/s, 30 000 × steps | {$fl:.2f} ($(range < lig.full)) | {$fg:.2f} ($(range < gf.full)) | {$fg / $fl:.2f} |')"
  echo "| spheres at the end (run 1) | $(lig_atoms lig.dis.t1) | $(gf_atoms gf.t1/timeseries.csv) | |"
  echo
  echo "grainflow ÷ LIGGGHTS (spheres present), round by round: $(paste -d' ' gf.speeds lig.speeds | awk '{printf "%s%.2f", (NR > 1 ? " / " : ""), $1 / $2}')"
  echo
  echo "Spheres present: each code's own count summed over the steps (every 100 steps; LIGGGHTS's fill every 2 000),"
  echo "over its wall time (LIGGGHTS: loop times of its fill, settling and discharge runs; grainflow: \`wall time\`)."
} > "$new"
if [ -f "$out" ]; then
  { cat "$new"; echo; cat "$out"; } > "$out.tmp"
else
  cp "$new" "$out.tmp"
fi
mv "$out.tmp" "$out"
cat "$new"
exit
}
