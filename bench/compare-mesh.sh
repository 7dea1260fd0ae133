#!/usr/bin/env bash
# grainflow against LIGGGHTS 3.8 on triangle-mesh walls (issue #28), in the same session: the
# hopper discharge of 30 000 spheres with the same conical surface as 520, 9 976 and 99 552
# triangles, and the drum of 15 750 spheres turning at 1 rev/s (12 096 triangles). Inputs and
# settled states: bench/liggghts-mesh, the settled states in $SETTLED; grainflow's cases: bench/cases/hopper_*.toml,
# bench/cases/drum.toml. The STL files (38 MB) are generated into the work folder by the peers'
# make_geometry.py and checked against its checksums.
#
# Speed: particle-steps per second (N × steps / the timed loop's wall time), LIGGGHTS on one core
# (OMP_NUM_THREADS=1), grainflow on 1 thread (-j 1), median of RUNS rounds in which each code
# runs once, in turn, with grainflow ÷ LIGGGHTS (also round by round); the hopper's step time at
# each mesh relative to the 520-triangle mesh, for both codes; where the step goes: grainflow's
# mesh stage (all of its mesh-wall work: candidates, contacts, forces; as `grainflow run`
# prints it if its stages line has it, else from `perf record` of one more run: the share of
# `Simulation::advance` under `mesh_loads`), LIGGGHTS's "Other" time (its fixes, mesh walls among
# them); and, from the same state, both codes' translational kinetic energy at the end of the
# timed window (different trajectories of a chaotic flow: a check of the physics, not a match).
#
# Timed window. The hopper's spheres leave the box 30 mm below the orifice: LIGGGHTS deletes
# them, grainflow stops the run. The first leaves at step 2 800-3 000 from the settled state (in
# both codes), so both codes are timed over HOPPER_WARM = 500 untimed + HOPPER_RUN = 2 000 timed
# steps, all 30 000 spheres in the box (LIGGGHTS's own timing round, 10 000 + 2 000 steps of
# steady discharge, is not possible in grainflow before it has outlets; a deeper box would keep
# the spheres, but they would fall ~0.4 m and reach 2.8 m/s, and the fastest sphere sets how
# often both codes rebuild their neighbour lists). The drum: DRUM_WARM = 1 000 + DRUM_RUN = 2 000
# steps from drum_rotating.data, as the peer's README. grainflow's untimed steps are one run
# that writes a checkpoint; every timed run restarts from it (a restart continues bit for bit,
# contact histories included), so its wall time is that of the timed steps alone, as
# LIGGGHTS's second `run`. A case grainflow refuses (the drum needs [meshes.motion]) is
# reported as not run.
#
# Results go on top of bench/results/<date>-mesh.md (the day's earlier runs stay below).
#
#   bench/compare-mesh.sh          (RUNS=3; CASES="hopper_500 hopper_10k hopper_100k drum";
#                                   PERF=0 skips the perf runs; CARGO= the cargo command)
set -euo pipefail
# One block, read whole before it runs (an edit of this file during a run changes nothing).
{
cd "$(dirname "$0")/.."
ROOT=$PWD
MP=${MP:-$ROOT/bench/liggghts-mesh}
# The settled LIGGGHTS states (MB-sized data files) stay outside the repository.
SETTLED=${SETTLED:-$ROOT/../shared/peers/liggghts-mesh}
RUNS=${RUNS:-3}
CASES=${CASES:-"hopper_500 hopper_10k hopper_100k drum"}
HOPPER_WARM=${HOPPER_WARM:-500}
HOPPER_RUN=${HOPPER_RUN:-2000}
DRUM_WARM=${DRUM_WARM:-1000}
DRUM_RUN=${DRUM_RUN:-2000}
PERF=${PERF:-1}
CARGO=${CARGO:-cargo}
DT=2e-5
mkdir -p bench/results
if ! command -v liggghts >/dev/null; then
  apt-get update -qq && apt-get install -y -qq --no-install-recommends liggghts >/dev/null
fi
if [ "$PERF" = 1 ] && ! command -v perf >/dev/null; then
  echo "perf not found: no mesh-stage share (PERF=0)" >&2
  PERF=0
fi
$CARGO build --release --quiet
GF=$ROOT/target/release/grainflow
W=$(mktemp -d)
trap 'rm -rf "$W"' EXIT

# Geometry and states: the STLs as the peer generates them, the settled states as shipped.
mkdir -p "$W/data"
python3 "$MP/make_geometry.py" "$W/data" >/dev/null
(cd "$W/data" && sha256sum --quiet -c "$MP/stl.sha256") || echo "warning: the STL files differ from $MP/stl.sha256" >&2
ln -s "$SETTLED"/*.data "$W/data/"
cd "$W"

median() { sort -g | awk '{a[NR]=$1} END {print (NR%2) ? a[(NR+1)/2] : (a[NR/2]+a[NR/2+1])/2}'; }
range() { sort -g | awk 'NR==1{lo=$1} {hi=$1} END {printf "%.2f–%.2f", lo, hi}'; }
# LIGGGHTS's log: the timed run is the last `run`. Loop time, atoms, its "Other" share, its
# neighbour-list builds, and the last thermo row's KinEng (found by its header).
lig_loop() { awk '/^Loop time of/{t=$4; for(k=1;k<=NF;k++) if($k=="with") n=$(k+1)} END {print t, n}' "$1"; }
lig_other() { awk '/^Other +time/{s=$NF} END {gsub(/[()]/,"",s); print s}' "$1"; }
lig_builds() { awk '/^Neighbor list builds/{b=$NF} END {print b}' "$1"; }
lig_ke() { awk '/^ *Step /{f=1; for(j=1;j<=NF;j++) if($j=="KinEng") col=j; next} /^Loop time/{f=0}
                f && $1 ~ /^[0-9]+$/ {k=$col} END {print k}' "$1"; }
gf_speed() { awk '/particle-steps\/s on/{for(k=1;k<=NF;k++) if($k=="particle-steps/s") print $(k-1)}' "$1"; }
gf_builds() { awk '/^neighbour list:/{for(k=1;k<=NF;k++) if($k=="rebuilt") print $(k+1)}' "$1"; }
# perf's report of a grainflow run: the share of Simulation::advance (the steps) spent under
# mesh_loads (the mesh stage, inlined), summed over the functions' copies.
mesh_share() {
  perf report -i "$1" --children --sort symbol --stdio --no-call-graph 2>/dev/null |
    awk '/\[\.\]/ {p=$1; sub("%","",p); s=$0; sub(/ +- +- *$/,"",s); sub(/ +$/,"",s)
                   if (s ~ /::Simulation::advance$/) a+=p; if (s ~ /::mesh_loads( \(inlined\))?$/) m+=p}
         END {if (a > 0) printf "%.1f\n", 100*m/a; else print "-"}'
}

out="$ROOT/bench/results/$(date +%Y-%m-%d)-mesh.md"
new="$W/section.md"
{
  echo "# grainflow vs LIGGGHTS on mesh walls, $(date -u +%Y-%m-%dT%H:%MZ)"
  echo
  echo "Machine: $(lscpu | awk -F: '/Model name/{gsub(/^ +/,"",$2); print $2}'), $(nproc) cores, $(free -g | awk '/Mem/{print $2}') GiB;"
  echo "$(liggghts -h 2>/dev/null | sed -n 's/.*(Version \(.*\), compiled.*/\1/p' | head -1) on one core (OMP_NUM_THREADS=1); grainflow $($GF --version | awk '{print $2}') (-j 1), git $(git -C "$ROOT" rev-parse --short HEAD)."
  echo "Hopper: $HOPPER_WARM untimed + $HOPPER_RUN timed steps from the settled state (all 30 000 spheres in the box);"
  echo "drum: $DRUM_WARM + $DRUM_RUN from drum_rotating.data. Speeds in millions of particle-steps per second, median (range) of"
  echo "$RUNS rounds in which each code ran once, in turn."
  echo
  echo "| case | triangles | N | LIGGGHTS | grainflow | grainflow ÷ LIGGGHTS | ms/step LIGGGHTS | ms/step grainflow | step time ÷ 520 triangles, LIGGGHTS | grainflow | grainflow's mesh stage, % of step | LIGGGHTS \"Other\", % | neighbour builds LIGGGHTS / grainflow | KE at the end, LIGGGHTS | grainflow | rel. diff |"
  echo "|---|---|---|---|---|---|---|---|---|---|---|---|---|---|---|---|"
} > "$new"
: > rounds.md
: > notes.md
ms500_l=; ms500_g=
for c in $CASES; do
  case $c in
    hopper_*) m=${c#hopper_}; nw=$HOPPER_WARM; nr=$HOPPER_RUN
              lig_in="$MP/in.hopper_discharge.liggghts -var mesh $m -var data data/hopper_${m}_settled.data"
              stl=data/hopper_$m.stl ;;
    drum)     nw=$DRUM_WARM; nr=$DRUM_RUN
              lig_in="$MP/in.drum_rotate.liggghts -var data data/drum_rotating.data"
              stl=data/drum.stl ;;
    *) echo "unknown case $c" >&2; exit 2 ;;
  esac
  tri=$(grep -c '^ *facet normal' "$stl")
  # grainflow's untimed steps: one run writing its checkpoint at step nw (the run goes one
  # step beyond: a checkpoint is written only before a run's last step).
  case_t() { sed "s|^t_stop = .*|t_stop = $(python3 -c "print(($1 - 0.5) * $DT)")|; s|^interval = .*|interval = 1e9|" "$ROOT/bench/cases/$c.toml"; }
  case_t $((nw + 1)) > $c.warm.toml
  case_t $((nw + nr)) > $c.timed.toml
  if ! $GF run $c.warm.toml -j 1 --out gf.$c.warm -q --checkpoint-every $nw > gf.$c.warm.log 2>&1; then
    why=$( (grep -m1 'unknown field' gf.$c.warm.log || grep -m1 -i 'error' gf.$c.warm.log) | tr '|' '/' | sed 's/^ *//' | cut -c1-160)
    echo "| $c | $(printf %s "$tri" | sed ':a;s/\B[0-9]\{3\}\>/ &/;ta') | – | not run: grainflow refuses the case ($why) | | | | | | | | | | | | |" >> "$new"
    continue
  fi
  gf_restart() { $GF run $c.timed.toml -j 1 -q --restart gf.$c.warm/checkpoint.gfc --accept-changed-case "$@"; }
  rm -f lig.$c.speeds gf.$c.speeds
  for i in $(seq "$RUNS"); do
    OMP_NUM_THREADS=1 liggghts -in $lig_in -var mdir data -var idir "$MP" -var nwarm $nw -var nrun $nr \
      -log lig.$c.t$i > lig.$c.t$i.screen 2>&1
    read -r lt ln < <(lig_loop lig.$c.t$i)
    python3 -c "print($ln * $nr / $lt / 1e6)" >> lig.$c.speeds
    gf_restart --out gf.$c.t$i > gf.$c.t$i.log
    python3 -c "print($(gf_speed gf.$c.t$i.log) / 1e6)" >> gf.$c.speeds
  done
  n=$(lig_loop lig.$c.t1 | cut -d' ' -f2)
  ke_l=$(lig_ke lig.$c.t1)
  ke_g=$(awk -F, 'END {print $3}' gf.$c.t1/timeseries.csv)
  # The mesh stage's share of the step: as `grainflow run` prints it, once its stages line has
  # the meshes (the engine times them; the line printed walls, pairs … without them so far),
  # else from perf.
  share=$(awk '/^stages:/ {for(k=1;k<=NF;k++) if($k ~ /^mesh/) {p=$(k+4); gsub(/[(%),]/,"",p); print p}}' gf.$c.t1.log)
  share=${share:--}
  if [ "$share" = - ] && [ "$PERF" = 1 ]; then
    perf record -q -F 200 --call-graph dwarf,16384 -o perf.$c.data -- \
      $GF run $c.timed.toml -j 1 -q --restart gf.$c.warm/checkpoint.gfc --accept-changed-case --out gf.$c.perf > /dev/null 2>&1
    share=$(mesh_share perf.$c.data)
  fi
  echo "- $c: $(paste -d' ' gf.$c.speeds lig.$c.speeds | awk '{printf "%s%.2f", (NR > 1 ? " / " : ""), $1 / $2}')" >> rounds.md
  sl=$(median < lig.$c.speeds); sg=$(median < gf.$c.speeds)
  ms_l=$(python3 -c "print($n / ($sl * 1e6) * 1e3)"); ms_g=$(python3 -c "print($n / ($sg * 1e6) * 1e3)")
  if [ "$c" = hopper_500 ]; then ms500_l=$ms_l; ms500_g=$ms_g; fi
  rel_l=-; rel_g=-
  if [[ $c == hopper_* && -n $ms500_l ]]; then
    rel_l=$(python3 -c "print(f'{$ms_l / $ms500_l:.2f}')"); rel_g=$(python3 -c "print(f'{$ms_g / $ms500_g:.2f}')")
  fi
  python3 - "$c" "$tri" "$n" "$sl" "$(range < lig.$c.speeds)" "$sg" "$(range < gf.$c.speeds)" "$ms_l" "$ms_g" \
    "$rel_l" "$rel_g" "$share" "$(lig_other lig.$c.t1)" "$(lig_builds lig.$c.t1)" "$(gf_builds gf.$c.t1.log)" \
    "$ke_l" "$ke_g" >> "$new" <<'PY'
import sys
c, tri, n, sl, rl, sg, rg, ml, mg, xl, xg, share, other, bl, bg, kl, kg = sys.argv[1:]
sl, sg, ml, mg, kl, kg = map(float, (sl, sg, ml, mg, kl, kg))
print(f"| {c} | {int(tri):,} | {int(n):,} | {sl:.2f} ({rl}) | {sg:.2f} ({rg}) | {sg/sl:.2f} | {ml:.2f} | {mg:.2f} | {xl} | {xg} "
      f"| {share} | {float(other):.0f} | {bl} / {bg} | {kl:.6e} | {kg:.6e} | {(kg-kl)/kl:+.1e} |".replace(",", " "))
PY
done
{
  echo
  echo "grainflow ÷ LIGGGHTS, round by round:"
  echo
  cat rounds.md
  echo
  echo "N: spheres in the timed run (LIGGGHTS's count at its end; grainflow has the same). Step time"
  echo "÷ 520 triangles: the hopper's ms per step over the 520-triangle mesh's, each code its own."
  echo "grainflow's mesh stage: as \`grainflow run\` prints it, or (while its stages line lacks it) from one more"
  echo "run under \`perf record\` (dwarf call graphs), the samples under \`mesh_loads\` ÷ those under \`Simulation::advance\`. LIGGGHTS \"Other\": its timed run's"
  echo "Other time (fixes: mesh walls, gravity, integration; moving the mesh in the drum) ÷ loop time."
  echo "KE: translational kinetic energy at the window's end, from the same state in both codes."
} >> "$new"
if [ -f "$out" ]; then
  { cat "$new"; echo; cat "$out"; } > "$out.tmp"
else
  cp "$new" "$out.tmp"
fi
mv "$out.tmp" "$out"
cat "$new"
exit
}
