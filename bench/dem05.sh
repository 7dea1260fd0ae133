#!/usr/bin/env bash
# Times the whole `grainflow verify dem05` (both models, checks, CSV, both figures) over
# repeated runs and reports the median against MFIX 21.3's two DEM05 runs (0.34 s LSD +
# 2.97 s Hertz wall time on a machine like ours, optimised build). Needs hyperfine
# (apt-get install -y hyperfine).
set -euo pipefail
cd "$(dirname "$0")/.."
command -v hyperfine >/dev/null || { echo "hyperfine is needed: apt-get install -y hyperfine" >&2; exit 2; }
cargo build --release --quiet
out=$(mktemp -d)
json="$out/hyperfine.json"
hyperfine --warmup 2 --runs "${RUNS:-15}" --export-json "$json" \
  "./target/release/grainflow verify dem05 --out $out/results" >/dev/null
python3 - "$json" <<'PY'
import json, sys
r = json.load(open(sys.argv[1]))["results"][0]
med = r["median"]
mfix = 0.34 + 2.97
print(f"grainflow verify dem05: median {med:.3f} s over {len(r['times'])} runs "
      f"(min {r['min']:.3f}, max {r['max']:.3f}); MFIX 21.3 LSD + Hertz runs: {mfix:.2f} s; "
      f"speed-up {mfix / med:.1f}x")
PY
rm -rf "$out"
