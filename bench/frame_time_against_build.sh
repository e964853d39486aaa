#!/usr/bin/env bash
# Whole GI frame time of this build against another revision's, the two
# `terrain gi` commands run in alternation on the same fields: the real DEMs
# of `terrain_bench gi frame-time` (written by `gi write-dems`), 1x and 2x,
# under a uniform sky and under an equirectangular environment map
# (bench/sky_hdr.py), whose variation goes through the SH product in both.
# Each run: `--frames F --time --gi-incremental off --threads 2`, its median
# frame after a warm-up; the table gives the median over the rounds. Writes
# bench/results/gi_frame_time_against_build.md and .csv.
#
# Usage: bench/frame_time_against_build.sh REV [--rounds N] [--frames F] [--build-dir DIR] [--other-build DIR]
#   REV: the revision to compare with, e.g. b2d20a2 (the engine the day the
#   exact ambient's work began); its `terrain` is built in a temporary worktree,
#   or taken from --other-build DIR (a Release build of REV made before).
set -euo pipefail
cd "$(dirname "$0")/.."
rev=${1:?usage: bench/frame_time_against_build.sh REV [--rounds N] [--frames F] [--build-dir DIR]}
shift
rounds=5 frames=10 B=build other=
while [ $# -gt 0 ]; do
  case "$1" in
    --rounds) rounds=$2; shift 2 ;;
    --frames) frames=$2; shift 2 ;;
    --build-dir) B=$2; shift 2 ;;
    --other-build) other=$2; shift 2 ;;
    *) echo "frame_time_against_build.sh: unknown option '$1'" >&2; exit 2 ;;
  esac
done
rev_hash=$(git rev-parse --short "$rev^{commit}")
head_hash=$(git rev-parse --short HEAD)
work=$(mktemp -d)
cleanup() { git worktree remove --force "$work/tree" >/dev/null 2>&1 || true; rm -rf "$work"; }
trap cleanup EXIT

if [ -n "$other" ]; then
  mkdir -p "$work/build" && ln -s "$(cd "$other" && pwd)/terrain" "$work/build/terrain"
else
  echo "frame_time_against_build.sh: building $rev_hash's terrain in $work" >&2
  git worktree add --detach "$work/tree" "$rev_hash" >/dev/null 2>&1
  cmake -S "$work/tree" -B "$work/build" -DCMAKE_BUILD_TYPE=Release -DTERRAIN_BUILD_TESTS=OFF \
    -DTERRAIN_BUILD_BENCH=OFF -DTERRAIN_BUILD_PYTHON=OFF -DTERRAIN_WERROR=OFF >/dev/null
  cmake --build "$work/build" -j "$(nproc)" --target terrain >/dev/null
fi
cmake --build "$B" -j "$(nproc)" --target terrain terrain_bench >/dev/null
"$B/terrain_bench" --out "$work/dems" gi write-dems 2>/dev/null
python3 bench/sky_hdr.py "$work/sky.hdr"

# one run: its median ms per frame
frame_ms() {  # terrain dem cell subsample sky
  local light=()
  [ "$5" = env ] && light=(--light "env:$work/sky.hdr")
  "$1" gi --heightmap "$work/dems/$2" --cell-size "$3" --subsample "$4" "${light[@]}" --frames "$frames" --time \
    --gi-incremental off --threads 2 | awk '/ms per frame/ {print $1}'
}

csv=$work/runs.csv
echo "dem,subsample,sky,round,this_ms,other_ms" >"$csv"
for ((round = 1; round <= rounds; round++)); do
  while read -r dem cell; do
    for s in 1 2; do
      for sky in uniform env; do
        # alternate which build goes first, so that a drift falls on both alike
        if ((round % 2)); then
          a=$(frame_ms "$B/terrain" "$dem" "$cell" $s $sky); b=$(frame_ms "$work/build/terrain" "$dem" "$cell" $s $sky)
        else
          b=$(frame_ms "$work/build/terrain" "$dem" "$cell" $s $sky); a=$(frame_ms "$B/terrain" "$dem" "$cell" $s $sky)
        fi
        echo "${dem%.exr},$s,$sky,$round,$a,$b" | tee -a "$csv" >&2
      done
    done
  done <"$work/dems/dems.txt"
done

python3 - "$csv" "$rev_hash" "$head_hash" "$rounds" "$frames" <<'EOF'
import csv, os, statistics, subprocess, sys
path, rev, head, rounds, frames = sys.argv[1:]
rows = list(csv.DictReader(open(path)))
cases = {}
for r in rows:
    cases.setdefault((r["dem"], r["subsample"], r["sky"]), []).append((float(r["this_ms"]), float(r["other_ms"])))
cpu = next((l.split(":", 1)[1].strip() for l in open("/proc/cpuinfo") if l.startswith("model name")), "?")
md = ["# Whole GI frame time against the engine of another revision", "",
      f"This build ({head}) against {rev}, each `terrain gi --frames {frames} --time --gi-incremental off "
      f"--threads 2` on the same field, the two commands in alternation ({rounds} rounds, the order swapped every "
      "round); a run's time is its median frame after a warm-up, the table's the median over the rounds (and their "
      "range); ratio: of the two medians; ratio per round: the range of this build's time over the other's within "
      "one round (the two runs back to back). Fields: the real DEMs of `terrain_bench gi frame-time`. Skies: uniform (radiance 1) and an "
      "equirectangular environment map (bench/sky_hdr.py: sky gradient, ground, sun disc), whose variation goes "
      "through the SH product in both builds.", "",
      f"Machine: {cpu}, {os.cpu_count()} hardware threads. Command: `bench/frame_time_against_build.sh {rev} "
      f"--rounds {rounds} --frames {frames}`.", "",
      f"| DEM | s | sky | this build ms | range | {rev} ms | range | ratio | ratio per round |",
      "|---|---|---|---|---|---|---|---|---|"]
out = ["dem,subsample,sky,this_ms,other_ms,ratio"]
for (dem, s, sky), v in cases.items():
    a = statistics.median(x for x, _ in v); b = statistics.median(y for _, y in v)
    md.append(f"| {dem} | {s}x | {'environment map' if sky == 'env' else 'uniform'} | {a:.1f} | "
              f"{min(x for x, _ in v):.1f}-{max(x for x, _ in v):.1f} | {b:.1f} | "
              f"{min(y for _, y in v):.1f}-{max(y for _, y in v):.1f} | {a / b:.2f}x | "
              f"{min(x / y for x, y in v):.2f}-{max(x / y for x, y in v):.2f}x |")
    out.append(f"{dem},{s},{sky},{a:.2f},{b:.2f},{a / b:.3f}")
os.makedirs("bench/results", exist_ok=True)
open("bench/results/gi_frame_time_against_build.md", "w").write("\n".join(md) + "\n")
open("bench/results/gi_frame_time_against_build.csv", "w").write("\n".join(out) + "\n")
print("\n".join(md))
EOF
