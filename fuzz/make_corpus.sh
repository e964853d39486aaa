#!/usr/bin/env bash
# Writes the seed corpora fuzz/corpus/<target>/: small valid inputs, made by
# the engine itself where it writes the format (a 16 x 16 field: the albedo
# and exponent targets expect that size), the example scene files, and
# hand-written Radiance .hdr files (the engine reads that format, never
# writes it). Run again after a format change, review, commit.
# Usage: fuzz/make_corpus.sh path/to/terrain   (a normal build's binary)
set -euo pipefail
T=$(realpath "$1")
cd "$(dirname "$0")"
C=corpus
rm -rf "$C"
mkdir -p "$C"/{albedo_png,equirect_exr,equirect_hdr,exponent_png,exr_heightmap,geotiff,number_list,png_heightmap,scene_toml,vdb}
tmp=$(mktemp -d)
trap 'rm -rf "$tmp"' EXIT

# heightmaps and frames: 16-bit PNG, and .vdb with every layer (8 x 8: one
# leaf node per grid, the VDB files stay small)
for scene in erosion waves; do
  "$T" sim --scene $scene --size 16 --ticks 2 --seed 3 --out "$tmp/$scene" --format png --quiet
  "$T" sim --scene $scene --size 8 --ticks 2 --seed 3 --out "$tmp/$scene-vdb" --format vdb --quiet
  cp "$tmp/$scene/frame_000002.png" "$C/png_heightmap/$scene-16x16.png"
  cp "$tmp/$scene-vdb/frame_000002.vdb" "$C/vdb/$scene-8x8.vdb"
  # a float32 EXR frame: every layer a channel, `height` among them
  "$T" sim --scene $scene --size 8 --ticks 2 --seed 3 --out "$tmp/$scene-exr" --format exr --quiet
  cp "$tmp/$scene-exr/frame_000002.exr" "$C/exr_heightmap/$scene-8x8.exr"
done
"$T" sim --scene erosion --size 7 --ticks 1 --out "$tmp/small" --format png --quiet
cp "$tmp/small/frame_000001.png" "$C/png_heightmap/erosion-7x7.png"
cp "$C/png_heightmap/erosion-16x16.png" "$C/exponent_png/exponent-16x16.png"

# GI maps of the 16 x 16 field: the RGB shade as an sRGB PNG (an albedo map)
# and as half-float EXR (an environment map), the ambient map as a one-channel EXR
hm=(--heightmap "$C/png_heightmap/erosion-16x16.png" --cell-size 10 --z-scale 0.01)
"$T" gi "${hm[@]}" --out-shade "$tmp/shade.png" --out-ambient "$tmp/ambient.exr" >/dev/null
"$T" gi "${hm[@]}" --light sunsky --out-shade "$tmp/shade.exr" >/dev/null
cp "$tmp/shade.png" "$C/albedo_png/shade-16x16.png"
cp "$tmp/shade.exr" "$C/equirect_exr/shade-rgb.exr"
cp "$tmp/ambient.exr" "$C/equirect_exr/ambient-y.exr"
cp "$tmp/ambient.exr" "$C/exr_heightmap/ambient-half-y.exr"  # a single half-float channel

# GeoTIFF: int16 DEMs written by hand (tests/hand_geotiff.sh), one with
# nodata cells and one in degrees (the CRS error path), and what the engine
# writes from them: a DEFLATE-compressed, tiled float32 ambient map and RGB
# shade carrying the DEM's georeferencing
source ../tests/hand_geotiff.sh
hand_geotiff "$C/geotiff/dem-int16-12x10.tif" 12 10 utm32n
hand_geotiff "$C/geotiff/nodata-int16-8x8.tif" 8 8 utm32n -9999
hand_geotiff "$C/geotiff/wgs84-int16-4x4.tif" 4 4 wgs84
"$T" gi --heightmap "$C/geotiff/dem-int16-12x10.tif" --out-ambient "$C/geotiff/ambient-float32-12x10.tif" \
  --out-shade "$C/geotiff/shade-rgb-12x10.tif" >/dev/null

# Radiance RGBE: 2 x 4 flat pixels, and 16 x 2 run-length encoded scanlines
# (per channel: a run of 16 equal bytes, or 16 literal bytes)
hdr_header() { printf '#?RADIANCE\nFORMAT=32-bit_rle_rgbe\nEXPOSURE=1.0\n\n-Y %d +X %d\n' "$1" "$2"; }
{
  hdr_header 2 4
  for i in 0 1 2 3 4 5 6 7; do printf "\\x$((40 + 10 * i))\\x80\\x20\\x81"; done
} >"$C/equirect_hdr/flat-4x2.hdr"
{
  hdr_header 2 16
  for y in 0 1; do
    printf '\x02\x02\x00\x10'
    printf '\x90\x80'                                                                     # R: run of 16
    printf '\x10'; for x in $(seq 0 15); do printf "\\x$(printf %02x $((16 * x + y)))"; done  # G: 16 literals
    printf '\x90\x40\x90\x81'                                                             # B, E: runs
  done
} >"$C/equirect_hdr/rle-16x2.hdr"

# scene files: the examples (TOML with every table a scene may have)
cp ../scenes/*.toml "$C/scene_toml/"

# number lists as the command line takes them (albedo, key light, sun, ranges)
printf '0.7,0.6,0.5' >"$C/number_list/albedo"
printf '45,30,2,1,0.9,0.8' >"$C/number_list/key-light"
printf '9,1,45,172' >"$C/number_list/sun"
printf '1,1000' >"$C/number_list/range"
printf -- '-1.5e-3,+2.5E+2,0x1p-3,inf' >"$C/number_list/forms"

du -sh "$C"
