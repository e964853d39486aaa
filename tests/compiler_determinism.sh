#!/usr/bin/env bash
# Cross-compiler determinism: two terrain binaries (one built with GCC, one
# with Clang, say) must write byte-identical outputs for the same commands:
# the simulation's state hashes and frames (erosion and waves scenes, a scene
# file) and the GI's maps (1x and 2x receivers, 0 to 2 bounces, both indirect
# kernels, glossy indirect light, a sun and sky, the reference path).
# Floating point is pinned (no contraction, no fast-math), the SIMD paths use
# correctly rounded lane operations only, and the few libm calls are the same
# shared library for both, so any difference is a bug to chase.
# Usage: compiler_determinism.sh path/to/terrain-A path/to/terrain-B path/to/source
set -u
A=$(realpath "$1")  # absolute: each command runs in a folder of its own
B=$(realpath "$2")
SRC=$(realpath "$3")
pass=0
fail=0
tmp=$(mktemp -d)
trap 'rm -rf "$tmp"' EXIT

# A .vdb file's header holds a random UUID, new in every file written: 36
# characters after the 8-byte magic, 4-byte file version, two 4-byte library
# versions and the 1-byte grid-offsets flag. Blanked, the rest must match.
mask_vdb_uuids() {
  local f
  for f in $(find "$1" -name '*.vdb'); do
    head -c 36 /dev/zero | dd of="$f" bs=1 seek=21 conv=notrunc status=none
  done
}

# runs one command line (the arguments after the name) with each binary in a
# folder of its own, then compares stdout and every file written, byte for byte
compare() {
  local name=$1
  shift
  local side bin
  for side in a b; do
    bin=$A
    [ $side = b ] && bin=$B
    mkdir -p "$tmp/$side/$name"
    if ! (cd "$tmp/$side/$name" && "$bin" "$@" >stdout 2>stderr); then
      fail=$((fail + 1))
      echo "FAIL: $name: $bin exited non-zero: $(head -c 300 "$tmp/$side/$name/stderr")"
      return
    fi
    rm "$tmp/$side/$name/stderr"  # timings and progress differ between runs
    mask_vdb_uuids "$tmp/$side/$name"
  done
  local differ
  differ=$(diff -rq "$tmp/a/$name" "$tmp/b/$name" | sed "s|$tmp/[ab]/||g")
  if [ -z "$differ" ]; then
    pass=$((pass + 1))
  else
    fail=$((fail + 1))
    echo "FAIL: $name: outputs differ: $differ"
  fi
}

# ---- simulation: hash lines and frames (.vdb with every layer, 16-bit .png) ----
compare erosion sim --scene erosion --size 96 --ticks 40 --seed 5 --threads 2 --hash-every 10 --quiet \
  --out frames --out-every 20 --format both
compare waves sim --scene waves --size 96 --ticks 40 --seed 2 --threads 2 --hash-every 10 --quiet \
  --out frames --out-every 20 --format both
compare pit-lake sim --scene "$SRC/scenes/pit-lake.toml" --size 64 --ticks 30 --threads 2 --hash-every 10 --quiet

# ---- GI on an eroded field (binary A's frame; both read the same file) ----
field=$tmp/field.png
"$A" sim --scene erosion --size 96 --ticks 30 --seed 7 --threads 2 --out "$tmp/field" --format png --quiet \
  && cp "$(ls "$tmp/field"/*.png | tail -1)" "$field" || { echo "FAIL: could not make the GI field"; exit 1; }
hm=(--heightmap "$field" --cell-size 4 --z-scale 0.01 --threads 2)
maps=(--out-shade shade.exr --out-ambient ambient.npy)
ind=(--out-indirect indirect.npy)
compare gi-direct-1x gi "${hm[@]}" "${maps[@]}"
compare gi-direct-2x-bspline gi "${hm[@]}" "${maps[@]}" --subsample 2 --interp bspline --light sunsky
compare gi-bounce1-1x gi "${hm[@]}" "${maps[@]}" "${ind[@]}" --bounces 1 --albedo 0.6,0.5,0.4
compare gi-bounce2-2x gi "${hm[@]}" "${maps[@]}" "${ind[@]}" --bounces 2 --subsample 2 --albedo 0.7,0.7,0.7
compare gi-bounce2-sh gi "${hm[@]}" "${maps[@]}" "${ind[@]}" --bounces 2 --indirect-kernel sh
compare gi-glossy-vector gi "${hm[@]}" "${maps[@]}" "${ind[@]}" --bounces 1 --brdf mix:0.5,40 --glossy vector
compare gi-glossy-scalar-2x gi "${hm[@]}" "${maps[@]}" "${ind[@]}" --bounces 2 --subsample 2 \
  --brdf phong:20 --glossy scalar
compare gi-glossy-lobe gi "${hm[@]}" "${maps[@]}" "${ind[@]}" --bounces 2 --brdf mix:0.5,40 --glossy lobe
compare gi-sun-frames gi "${hm[@]}" "${maps[@]}" --sun 9,1,45,172 --frames 3 --bounces 1
compare gi-reference gi "${hm[@]}" --out-ambient ambient.npy --reference --bounces 1 \
  --reference-directions 64

echo "compiler_determinism: $pass passed, $fail failed"
[ "$fail" = 0 ]
