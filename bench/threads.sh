#!/usr/bin/env bash
# What grainflow's threads give (issue 39, item 4), all in one session, alternated rounds,
# medians of RUNS:
#   1. The shipped examples (examples/*/case.toml, whole runs): the default (every core, the
#      engine choosing per step whether the threads pay) against -j 1.
#   2. The mesh cases of compare-mesh.sh (the drum, hopper_10k; their settled states from
#      $SETTLED, the STLs from liggghts-mesh/make_geometry.py): -j 2 and the default against
#      -j 1, timed from a checkpoint after the untimed steps, as compare-mesh.sh does.
#   3. The plane-wall yardsticks (cases/box_hm, box_lsd, chute; the states compare-peers.sh
#      writes into cases/data): -j 1 and -j 2, and the same with $OLD (another grainflow
#      binary, e.g. one built at an earlier commit) beside them; and, in one process taking
#      turns (`alternate … 1,1x2,2`), 2 threads ÷ 1 beside two independent 1-thread copies ÷ 1.
# Speeds are particle-steps per second as `grainflow run` prints them (its timed loop).
# Writes results/<date>-threads.md (on top of the day's earlier runs).
#
#   bench/threads.sh    (RUNS=3; OLD=path/to/grainflow; PARTS="examples mesh yardsticks";
#                        SETTLED=…; CARGO="flock LOCK cargo" shares a build lock)
set -euo pipefail
{
cd "$(dirname "$0")/.."
ROOT=$PWD
RUNS=${RUNS:-3}
OLD=${OLD:-}
PARTS=${PARTS:-"examples mesh yardsticks"}
SETTLED=${SETTLED:-$ROOT/../shared/peers/liggghts-mesh}
DATA=$ROOT/bench/cases/data
CARGO=${CARGO:-cargo}
$CARGO build --release --quiet
$CARGO build --release --quiet -p grainflow-case --example alternate
GF=$ROOT/target/release/grainflow
ALT=$ROOT/target/release/examples/alternate
W=$(mktemp -d)
trap 'rm -rf "$W"' EXIT
cd "$W"

median() { sort -g | awk '{a[NR]=$1} END {print (NR%2) ? a[(NR+1)/2] : (a[NR/2]+a[NR/2+1])/2}'; }
speed() { awk '/particle-steps\/s on/{for(k=1;k<=NF;k++) if($k=="particle-steps/s") print $(k-1)/1e6}' "$1"; }
ratio() { python3 -c "print(f'{$1 / $2:.2f}')"; }
# The ratios a/b of two files of speeds, round by round.
rounds() { paste -d' ' "$1" "$2" | awk '{printf "%s%.2f", (NR > 1 ? " / " : ""), $1 / $2}'; }

out="$ROOT/bench/results/$(date +%Y-%m-%d)-threads.md"
new="$W/section.md"
{
  echo "# grainflow's threads, $(date -u +%Y-%m-%dT%H:%MZ)"
  echo
  echo "Machine: $(lscpu | awk -F: '/Model name/{gsub(/^ +/,"",$2); print $2}'), $(nproc) cores; grainflow $($GF --version | awk '{print $2}'), git $(git -C "$ROOT" rev-parse --short HEAD)${OLD:+; old: $OLD}."
  echo "Millions of particle-steps per second, median of $RUNS alternated rounds (ratios also round by round)."
} > "$new"

if [[ " $PARTS " == *" examples "* ]]; then
  {
    echo
    echo "## The shipped examples, whole runs: the default (every core, chosen per step) against -j 1"
    echo
    echo "| example | -j 1 | default | default ÷ -j 1 | rounds | what the engine chose (last round) |"
    echo "|---|---|---|---|---|---|"
  } >> "$new"
  for case in "$ROOT"/examples/*/case.toml; do
    e=$(basename "$(dirname "$case")")
    rm -f ex.$e.1 ex.$e.d
    for i in $(seq "$RUNS"); do
      (cd "$(dirname "$case")" && $GF run case.toml -q -j 1 --overwrite --out "$W/ex.$e.out1") > ex.$e.log1
      speed ex.$e.log1 >> ex.$e.1
      (cd "$(dirname "$case")" && $GF run case.toml -q --overwrite --out "$W/ex.$e.outd") > ex.$e.logd
      speed ex.$e.logd >> ex.$e.d
    done
    a=$(median < ex.$e.1); b=$(median < ex.$e.d)
    chose=$(grep -m1 '^threads chosen' ex.$e.logd | sed 's/^threads chosen by measured work (-j N fixes them): //' || true)
    echo "| $e | $a | $b | $(ratio "$b" "$a") | $(rounds ex.$e.d ex.$e.1) | ${chose:-on 1 thread (one core)} |" >> "$new"
  done
fi

if [[ " $PARTS " == *" mesh "* ]]; then
  mkdir -p data
  python3 "$ROOT/bench/liggghts-mesh/make_geometry.py" data >/dev/null
  ln -sf "$SETTLED"/*.data data/
  {
    echo
    echo "## Mesh cases (compare-mesh.sh's windows, timed from a checkpoint): -j 2 and the default against -j 1"
    echo
    echo "| case | -j 1 | -j 2 | default | -j 2 ÷ -j 1 | rounds | default ÷ -j 1 |"
    echo "|---|---|---|---|---|---|---|"
  } >> "$new"
  DT=2e-5
  for c in drum hopper_10k; do
    case $c in drum) nw=1000; nr=2000 ;; *) nw=500; nr=2000 ;; esac
    case_t() { sed "s|^t_stop = .*|t_stop = $(python3 -c "print(($1 - 0.5) * $DT)")|; s|^interval = .*|interval = 1e9|" "$ROOT/bench/cases/$c.toml"; }
    case_t $((nw + 1)) > $c.warm.toml
    case_t $((nw + nr)) > $c.timed.toml
    $GF run $c.warm.toml -j 1 --out gf.$c.warm -q --checkpoint-every $nw > /dev/null
    rm -f m.$c.1 m.$c.2 m.$c.d
    for i in $(seq "$RUNS"); do
      for j in 1 2 d; do
        flag=(-j "$j"); [ "$j" = d ] && flag=()
        rm -rf gf.$c.t
        $GF run $c.timed.toml "${flag[@]}" -q --restart gf.$c.warm/checkpoint.gfc --accept-changed-case --out gf.$c.t > m.$c.log$j
        speed m.$c.log$j >> m.$c.$j
      done
    done
    a=$(median < m.$c.1); b=$(median < m.$c.2); d=$(median < m.$c.d)
    echo "| $c | $a | $b | $d | $(ratio "$b" "$a") | $(rounds m.$c.2 m.$c.1) | $(ratio "$d" "$a") |" >> "$new"
  done
fi

if [[ " $PARTS " == *" yardsticks "* ]]; then
  {
    echo
    echo "## Plane-wall yardsticks, 2 000 steps from the settled states"
    echo
    echo "| case | -j 1 | -j 2 | 2 ÷ 1 |${OLD:+ old -j 1 | old -j 2 | -j 1 ÷ old | rounds | -j 2 ÷ old | rounds |} alternate: 2 threads ÷ 1 | two copies ÷ 1 | 2 threads ÷ two copies |"
    echo "|---|---|---|---|${OLD:+---|---|---|---|---|---|}---|---|---|"
  } >> "$new"
  for c in box_hm box_lsd chute; do
    steps=2000
    dt=$(awk -F'[= ]+' '/^dt =/{print $2; exit}' "$ROOT/bench/cases/$c.toml")
    sed "s|file = \"data/|file = \"$DATA/|; s|^t_stop = .*|t_stop = $(python3 -c "print(($steps + 0.5) * $dt)")|" "$ROOT/bench/cases/$c.toml" > $c.toml
    rm -f y.$c.*
    for i in $(seq "$RUNS"); do
      for j in 1 2; do
        rm -rf y.$c.out; $GF run $c.toml -j $j -q --out y.$c.out > y.$c.log; speed y.$c.log >> y.$c.$j
        if [ -n "$OLD" ]; then
          # (an older binary may not know --overwrite)
          rm -rf y.$c.out; $OLD run $c.toml -j $j -q --out y.$c.out > y.$c.olog; speed y.$c.olog >> y.$c.o$j
        fi
      done
    done
    a=$(median < y.$c.1); b=$(median < y.$c.2)
    row="| $c | $a | $b | $(ratio "$b" "$a") |"
    if [ -n "$OLD" ]; then
      oa=$(median < y.$c.o1); ob=$(median < y.$c.o2)
      row="$row $oa | $ob | $(ratio "$a" "$oa") | $(rounds y.$c.1 y.$c.o1) | $(ratio "$b" "$ob") | $(rounds y.$c.2 y.$c.o2) |"
    fi
    $ALT $c.toml 1,1x2,2 100 10 > y.$c.alt
    # The alternate tool's lines: each entry's speed as a multiple of the first's (1 thread).
    times() { awk -v re="$1" '$0 ~ re {for(k=1;k<=NF;k++) if($k=="times") {print $(k-1); exit}}' y.$c.alt; }
    s1=1; s12=$(times 'x 2 copies at once'); s2=$(times '^2 threads:')
    echo "$row $(ratio "$s2" "$s1") | $(ratio "$s12" "$s1") | $(ratio "$s2" "$s12") |" >> "$new"
  done
fi

mkdir -p "$ROOT/bench/results"
{ cat "$new"; echo; [ -f "$out" ] && cat "$out"; } > "$W/all.md"
mv "$W/all.md" "$out"
cat "$new"
}
