#!/usr/bin/env bash
# What continuous insertion and an outlet cost grainflow (issue #29): the hopper of
# bench/cases/hopper_10k.toml (9 976 triangles, 30 000 spheres settled, the orifice open) in a
# steady discharge two ways, alike but for the flow's books:
#   inflow:        bench/cases/hopper_steady_inflow.toml: an outlet 20 mm below the orifice
#                  removes the spheres, an insertion at the top brings RATE per second (default
#                  2 700, about the discharge rate) in batches every 100 steps, so the count
#                  stays near 30 000;
#   recirculating: bench/cases/hopper_recirculating.toml: no insertion, no outlet; the box is
#                  periodic in z, so the spheres falling through its floor come back through
#                  its top and fall onto the bed: 30 000 spheres throughout.
# Both run WARM untimed steps from the settled state (the flow starts: 10 000 steps, 0.2 s, as
# the peer's discharge timing), written as a checkpoint; every timed run restarts from it for
# RUN steps (a restart continues bit for bit, the insertion's stream included). The untimed run
# is the timed case itself, run to its end once with a checkpoint at step WARM (so RUN ≤ WARM):
# a restart of a changed case (--accept-changed-case, as compare-mesh.sh restarts a case whose
# t_stop it changed) is refused once an insertion or an outlet has changed the particles.
#
# Speed: particle-steps per second, the spheres present summed over the steps (inflow: from
# the time series' mass column every 100 steps, each row counting for the steps since the one
# before; recirculating: 30 000 × RUN) ÷ `wall time`, on 1 thread (-j 1), median of RUNS rounds
# in which both run once, in turn; the ratio inflow ÷ recirculating (target ≥ 0.9), also round
# by round. Beside it, a check that the flows are alike: the inflow's count over the window
# (mean, min–max), the spheres it removed and inserted, and both runs' neighbour-list builds
# (set by the fastest spheres).
#
# Results go on top of bench/results/<date>-insertion.md (the day's earlier runs stay below).
#
#   bench/insertion-overhead.sh        (RUNS=3; WARM=10000 RUN=5000 RATE=2700;
#                                       CARGO= the cargo command; MP= the LIGGGHTS mesh inputs, default bench/liggghts-mesh)
set -euo pipefail
# One block, read whole before it runs (an edit of this file during a run changes nothing).
{
cd "$(dirname "$0")/.."
ROOT=$PWD
MP=${MP:-$ROOT/bench/liggghts-mesh}
# The settled LIGGGHTS states (MB-sized data files) stay outside the repository.
SETTLED=${SETTLED:-$ROOT/../shared/peers/liggghts-mesh}
RUNS=${RUNS:-3}
WARM=${WARM:-10000}
RUN=${RUN:-5000}
RATE=${RATE:-2700}
CARGO=${CARGO:-cargo}
DT=2e-5
BEAD=1.0471975511965977e-5      # kg: 2500 × π/6 × (2 mm)³
N0=30000
mkdir -p bench/results
$CARGO build --release --quiet
GF=$ROOT/target/release/grainflow
W=$(mktemp -d)
trap 'rm -rf "$W"' EXIT
mkdir -p "$W/data"
python3 "$MP/make_geometry.py" "$W/data" >/dev/null
(cd "$W/data" && sha256sum --quiet -c "$MP/stl.sha256") || echo "warning: the STL files differ from $MP/stl.sha256" >&2
ln -s "$SETTLED/hopper_10k_settled.data" "$W/data/"
cd "$W"

median() { sort -g | awk '{a[NR]=$1} END {print (NR%2) ? a[(NR+1)/2] : (a[NR/2]+a[NR/2+1])/2}'; }
range() { sort -g | awk 'NR==1{lo=$1} {hi=$1} END {printf "%.2f–%.2f", lo, hi}'; }
gf_wall() { awk '/^wall time/{print $3}' "$1"; }
gf_builds() { awk '/^neighbour list:/{for(k=1;k<=NF;k++) if($k=="rebuilt") print $(k+1)}' "$1"; }
# The time series' spheres (mass ÷ one sphere's) from step WARM on: summed over the steps
# (the row at WARM is the checkpoint's state, counting for no step), mean, min, max; and the
# inserted and removed spheres over the rows after it.
gf_counts() {
  awk -F, -v m=$BEAD -v w=$WARM 'NR==1{for(j=1;j<=NF;j++) {if($j=="step") cs=j; if($j=="mass") cm=j; if($j=="inserted") ci=j; if($j=="removed") cr=j}; next}
                      $cs < w {next}
                      {c=int($cm/m+0.5); if (k++) {s+=c*($cs-prev); n+=$cs-prev; i+=$ci; r+=$cr}; prev=$cs
                       if (k==1 || c<lo) lo=c; if (k==1 || c>hi) hi=c}
                      END {printf "%.0f %.0f %d %d %d %d\n", s, s/n, lo, hi, i, r}' "$1"
}

if [ "$RUN" -gt "$WARM" ]; then
  echo "RUN ($RUN) must not exceed WARM ($WARM): the untimed run's checkpoint at step WARM would be overwritten" >&2
  exit 2
fi
cases="hopper_steady_inflow hopper_recirculating"
for c in $cases; do
  sed "s|^t_stop = .*|t_stop = $(python3 -c "print(($WARM + $RUN - 0.5) * $DT)")|; s|^rate = .*|rate = $RATE|" \
    "$ROOT/bench/cases/$c.toml" > $c.toml
  # The untimed steps: the whole run once, its checkpoint at step WARM (the only one: a
  # checkpoint is written only before a run's last step).
  $GF run $c.toml -j 1 --out gf.$c.warm -q --checkpoint-every $WARM > gf.$c.warm.log 2>&1
done
rm -f *.speeds rounds.txt
for i in $(seq "$RUNS"); do
  for c in $cases; do
    $GF run $c.toml -j 1 -q --restart gf.$c.warm/checkpoint.gfc --out gf.$c.t$i > gf.$c.t$i.log
    t=$(gf_wall gf.$c.t$i.log)
    if [ $c = hopper_steady_inflow ]; then
      ps=$(gf_counts gf.$c.t$i/timeseries.csv | cut -d' ' -f1)
    else
      ps=$((N0 * RUN))
    fi
    python3 -c "print($ps / $t / 1e6)" >> $c.speeds
  done
done
si=$(median < hopper_steady_inflow.speeds); sr=$(median < hopper_recirculating.speeds)
read -r _ mean lo hi ins rem < <(gf_counts gf.hopper_steady_inflow.t1/timeseries.csv)
out="$ROOT/bench/results/$(date +%Y-%m-%d)-insertion.md"
new="$W/section.md"
{
  echo "# grainflow: the cost of continuous insertion and an outlet, $(date -u +%Y-%m-%dT%H:%MZ)"
  echo
  echo "Machine: $(lscpu | awk -F: '/Model name/{gsub(/^ +/,"",$2); print $2}'), $(nproc) cores, $(free -g | awk '/Mem/{print $2}') GiB;"
  echo "grainflow $($GF --version | awk '{print $2}') (-j 1), git $(git -C "$ROOT" rev-parse --short HEAD). Hopper of 9 976 triangles discharging from"
  echo "its settled 30 000 spheres: $WARM untimed steps, then $RUN timed; insertion $RATE spheres/s. Millions of particle-steps"
  echo "per second, median (range) of $RUNS rounds in which both ran once, in turn."
  echo
  echo "| | inflow (insertion + outlet) | recirculating (periodic z) | inflow ÷ recirculating (target ≥ 0.9) |"
  echo "|---|---|---|---|"
  python3 -c "print(f'| particle-steps/s | {$si:.2f} ($(range < hopper_steady_inflow.speeds)) | {$sr:.2f} ($(range < hopper_recirculating.speeds)) | {$si / $sr:.2f} |')"
  echo "| spheres in the window, mean (min–max) | $mean ($lo–$hi) | $N0 | |"
  echo "| inserted / removed in the window | $ins / $rem | – | |"
  echo "| neighbour-list builds in the window (run 1) | $(gf_builds gf.hopper_steady_inflow.t1.log) | $(gf_builds gf.hopper_recirculating.t1.log) | |"
  echo
  echo "inflow ÷ recirculating, round by round: $(paste -d' ' hopper_steady_inflow.speeds hopper_recirculating.speeds | awk '{printf "%s%.2f", (NR > 1 ? " / " : ""), $1 / $2}')"
  if grep -qi 'not fit\|did not' gf.hopper_steady_inflow.t1.log; then
    echo
    echo "The insertion reported: $(grep -i 'not fit\|did not' gf.hopper_steady_inflow.t1.log | head -1)"
  fi
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
