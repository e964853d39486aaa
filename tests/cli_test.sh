#!/usr/bin/env bash
# End-to-end checks of build/terrain: help texts, determinism across thread
# counts through the CLI, outputs, and one-line errors on bad input.
# Usage: cli_test.sh path/to/terrain path/to/source
set -u
T=$1
SRC=$2
pass=0
fail=0
ok() { pass=$((pass + 1)); }
bad() { fail=$((fail + 1)); echo "FAIL: $*"; }
tmp=$(mktemp -d)
trap 'chmod -R u+w "$tmp" 2>/dev/null; rm -rf "$tmp"' EXIT

# --help for the tool and every subcommand
"$T" --help >/dev/null 2>&1 && ok || bad "terrain --help"
for sub in $("$T" --help 2>/dev/null | awk '/^SUBCOMMANDS:/{f=1;next} f&&NF{print $1}'); do
  if "$T" "$sub" --help >"$tmp/help" 2>&1 && grep -q -- "--" "$tmp/help"; then ok; else bad "terrain $sub --help"; fi
done

# determinism: identical hash lines for 1, 2, 3 and 8 threads, and across runs
for scene in erosion waves; do
  "$T" sim --scene $scene --size 75 --ticks 20 --seed 3 --threads 1 --hash-every 5 --quiet >"$tmp/ref" 2>&1
  if [ "$(grep -c '^tick [0-9]* hash [0-9a-f]\{16\}$' "$tmp/ref")" = 4 ]; then ok; else bad "$scene hash lines: $(cat "$tmp/ref")"; fi
  for k in 2 3 8 1; do
    "$T" sim --scene $scene --size 75 --ticks 20 --seed 3 --threads $k --hash-every 5 --quiet >"$tmp/out" 2>&1
    if cmp -s "$tmp/ref" "$tmp/out"; then ok; else bad "$scene hashes differ with $k threads"; fi
  done
done

# frames: one .vdb per written frame, readable back as a heightmap
"$T" sim --scene erosion --size 40 --ticks 4 --out-every 2 --out "$tmp/frames" --format both --quiet >/dev/null 2>&1 \
  && [ "$(ls "$tmp/frames"/*.vdb | wc -l)" = 3 ] && [ "$(ls "$tmp/frames"/*.png | wc -l)" = 3 ] && ok || bad "sim --out frames"
ls "$tmp/frames" | grep -q tmp && bad "temporary files left in the output folder" || ok

# a requested step above the limit is reported (on stdout: stderr carries errors only) and clamped
"$T" sim --scene waves --size 32 --ticks 1 --dt 100 --quiet >"$tmp/out" 2>"$tmp/err" && grep -q "clamped" "$tmp/out" \
  && [ ! -s "$tmp/err" ] && ok || bad "dt clamp message: $(cat "$tmp/out" "$tmp/err")"

# one clear error line, exit 1, on bad input
expect_error() {  # description, pattern, command...
  local what=$1 pattern=$2
  shift 2
  "$@" >"$tmp/o" 2>"$tmp/e"
  local rc=$?
  if [ $rc -eq 1 ] && [ "$(wc -l <"$tmp/e")" = 1 ] && grep -q "^terrain: error: " "$tmp/e" && grep -q -- "$pattern" "$tmp/e"
  then ok; else bad "$what: rc=$rc stderr=$(cat "$tmp/e")"; fi
}
expect_error "bad scene" "unknown scene" "$T" sim --scene volcano --ticks 1
expect_error "absurd size" "size" "$T" sim --scene erosion --size 100000 --ticks 1
expect_error "zero size" "size" "$T" sim --scene erosion --size 0 --ticks 1
expect_error "negative ticks" "ticks" "$T" sim --scene erosion --ticks -5
expect_error "missing scene file" "missing.toml" "$T" sim --scene "$tmp/missing.toml" --ticks 1
printf 'base = "erosion"\n[thermal]\ntalus = 30\n' >"$tmp/typo.toml"
expect_error "scene file typo" "thermal.talus" "$T" sim --scene "$tmp/typo.toml" --ticks 1
mkdir -p "$tmp/ro"
chmod a-w "$tmp/ro"
if [ "$(id -u)" != 0 ]; then
  expect_error "unwritable output" "not writable" "$T" sim --scene erosion --size 16 --ticks 1 --out "$tmp/ro"
fi
expect_error "uncreatable output" "output folder" "$T" sim --scene erosion --size 16 --ticks 1 --out /proc/terrain-out
touch "$tmp/afile"
expect_error "output is a file" "afile" "$T" sim --scene erosion --size 16 --ticks 1 --out "$tmp/afile/sub"

# glossy GI: heightmaps (16-bit PNG) from the simulator double as exponent maps
"$T" sim --scene erosion --size 24 --ticks 1 --out "$tmp/g24" --format png --quiet >/dev/null 2>&1
"$T" sim --scene erosion --size 16 --ticks 1 --out "$tmp/g16" --format png --quiet >/dev/null 2>&1
hm24="$tmp/g24/frame_000000.png"
hm16="$tmp/g16/frame_000000.png"
"$T" gi --heightmap "$hm24" --cell-size 10 --brdf phong:20 --bounces 1 --glossy vector --phong-exponent "$hm24" \
  --out-indirect "$tmp/gv.npy" >/dev/null 2>&1 && [ -s "$tmp/gv.npy" ] && ok || bad "gi --glossy vector with an exponent map"
"$T" gi --heightmap "$hm24" --cell-size 10 --brdf mix:0.5,30 --bounces 1 --reference --reference-directions 128 \
  --reference-lobe-rings 6 \
  --out-indirect "$tmp/gr.npy" >/dev/null 2>&1 && [ -s "$tmp/gr.npy" ] && ok || bad "gi --reference with a glossy BRDF"
# the paper's linear glossy values stay reachable
"$T" gi --heightmap "$hm24" --cell-size 10 --brdf phong:64 --bounces 1 --glossy vector --glossy-positivity off \
  --out-indirect "$tmp/goff.npy" >/dev/null 2>&1 && [ -s "$tmp/goff.npy" ] && ok || bad "gi --glossy-positivity off"
# the lobe gather, and its quadrature out of range
"$T" gi --heightmap "$hm24" --cell-size 10 --brdf phong:64 --bounces 2 --glossy lobe --glossy-lobe-rings 2 \
  --glossy-lobe-azimuths 16 --phong-exponent "$hm24" --out-indirect "$tmp/globe.npy" >/dev/null 2>&1 &&
  [ -s "$tmp/globe.npy" ] && ok || bad "gi --glossy lobe"
expect_error "glossy lobe rings out of range" "glossy-lobe-rings" "$T" gi --heightmap "$hm24" --cell-size 10 \
  --brdf phong:20 --glossy lobe --glossy-lobe-rings 17
expect_error "glossy lobe inner directions out of range" "glossy-lobe-inner-directions" "$T" gi --heightmap "$hm24" \
  --cell-size 10 --brdf phong:20 --glossy lobe --glossy-lobe-inner-directions 2
expect_error "glossy lobe azimuths out of range" "glossy-lobe-azimuths" "$T" gi --heightmap "$hm24" --cell-size 10 \
  --brdf phong:20 --glossy lobe --glossy-lobe-azimuths 100000
expect_error "lobe rings out of range" "reference-lobe-rings" "$T" gi --heightmap "$hm24" --cell-size 10 \
  --brdf phong:20 --reference --reference-lobe-rings 0
expect_error "bad glossy positivity" "glossy-positivity" "$T" gi --heightmap "$hm24" --cell-size 10 --brdf phong:20 \
  --glossy-positivity maybe
expect_error "exponent map of the wrong size" "16 x 16 pixels" "$T" gi --heightmap "$hm24" --cell-size 10 --brdf phong:20 \
  --bounces 1 --phong-exponent "$hm16"
expect_error "unreadable exponent map" "missing.png" "$T" gi --heightmap "$hm24" --cell-size 10 --brdf phong:20 \
  --phong-exponent "$tmp/missing.png"
printf 'not a png' >"$tmp/bogus.png"
expect_error "exponent file that is not a PNG" "bogus.png" "$T" gi --heightmap "$hm24" --cell-size 10 --brdf phong:20 \
  --phong-exponent "$tmp/bogus.png"
expect_error "constant exponent out of range" "phong-exponent" "$T" gi --heightmap "$hm24" --cell-size 10 --phong-exponent -3
expect_error "bad exponent range" "phong-exponent-range" "$T" gi --heightmap "$hm24" --cell-size 10 --phong-exponent "$hm24" \
  --phong-exponent-range 100,10
expect_error "bad glossy mode" "glossy" "$T" gi --heightmap "$hm24" --cell-size 10 --glossy shiny
# the indirect kernel and azimuths: both kernels run, bad values are one error line
for k in sh blocker; do
  "$T" gi --heightmap "$hm24" --cell-size 10 --subsample 2 --bounces 1 --indirect-kernel $k --indirect-azimuths 12 \
    --out-indirect "$tmp/ik_$k.npy" >/dev/null 2>&1 && [ -s "$tmp/ik_$k.npy" ] && ok || bad "gi --indirect-kernel $k"
done
expect_error "bad indirect kernel" "indirect-kernel" "$T" gi --heightmap "$hm24" --cell-size 10 --bounces 1 --indirect-kernel cosine
expect_error "retired indirect kernel" "indirect-kernel" "$T" gi --heightmap "$hm24" --cell-size 10 --bounces 1 --indirect-kernel exact
expect_error "bad indirect azimuths" "--indirect-azimuths must be 0 or" "$T" gi --heightmap "$hm24" --cell-size 10 --bounces 1 --indirect-azimuths 2
expect_error "GI tolerance out of range" "--gi-tolerance must be in" "$T" gi --heightmap "$hm24" --cell-size 10 --gi-tolerance 2
# the same field twice: the second frame of incremental GI does nothing, and the outputs equal a full frame's
"$T" gi --heightmap "$hm24" --cell-size 10 --bounces 1 --frames 2 --out-indirect "$tmp/inc_on.npy" >/dev/null 2>&1 &&
  "$T" gi --heightmap "$hm24" --cell-size 10 --bounces 1 --frames 2 --gi-incremental off --out-indirect "$tmp/inc_off.npy" >/dev/null 2>&1 &&
  cmp -s "$tmp/inc_on.npy" "$tmp/inc_off.npy" && ok || bad "gi --gi-incremental on and off differ"

# gi: numbers out of range fail before any input is read; results are finite or not written
gi24=("$T" gi --heightmap "$hm24")
"${gi24[@]}" --cell-size 20 --out-ambient "$tmp/o.npy" >"$tmp/o" 2>"$tmp/e" && [ -s "$tmp/o.npy" ] && [ ! -s "$tmp/e" ] \
  && grep -q "terrain gi: .*24 x 24 cells" "$tmp/o" && ok || bad "gi: info on stdout, nothing on stderr: $(cat "$tmp/e")"
cp "$tmp/o.npy" "$tmp/o.good"
expect_error "tiny cell size" "--cell-size must be 0 or \[0.001, 1e+06\] (got 1e-38)" "${gi24[@]}" --cell-size 1e-38 --out-ambient "$tmp/o.npy"
expect_error "negative cell size" "--cell-size" "${gi24[@]}" --cell-size -10 --out-ambient "$tmp/o.npy"
expect_error "huge key light" "key light 1 rgb must be in \[0, 1e+06\]" "${gi24[@]}" --cell-size 10 --bounces 1 \
  --key 0,45,3,1e38,1e38,1e38 --out-ambient "$tmp/o.npy"
expect_error "nan key light" "'nan' is not finite" "${gi24[@]}" --cell-size 10 --key 0,45,3,nan,1,1 --out-ambient "$tmp/o.npy"
expect_error "huge sky" "environment intensity" "${gi24[@]}" --cell-size 10 --light-intensity 1e30 --out-ambient "$tmp/o.npy"
expect_error "nan exposure" "--exposure" "${gi24[@]}" --cell-size 10 --exposure nan --out-shade "$tmp/s.png"
expect_error "huge z scale" "--z-scale" "${gi24[@]}" --cell-size 10 --z-scale 1e30 --out-ambient "$tmp/o.npy"
expect_error "negative level offset" "--level-offset must be in \[0, 32\] (got -2)" "${gi24[@]}" --cell-size 10 --level-offset -2
expect_error "negative indirect azimuths" "--indirect-azimuths must be 0 or" "${gi24[@]}" --cell-size 10 --bounces 1 \
  --indirect-azimuths -5
expect_error "indirect without bounces" "needs --bounces" "${gi24[@]}" --cell-size 10 --out-ambient "$tmp/o.npy" \
  --out-indirect "$tmp/i.npy"
expect_error "indirect into a missing folder" "folder does not exist" "${gi24[@]}" --cell-size 10 --bounces 1 \
  --out-ambient "$tmp/o.npy" --out-indirect "$tmp/nowhere/i.npy"
mkdir -p "$tmp/adir.npy"
expect_error "output that is a folder" "is a folder" "${gi24[@]}" --cell-size 10 --out-ambient "$tmp/adir.npy"
cmp -s "$tmp/o.npy" "$tmp/o.good" && ok || bad "a failing gi run changed o.npy"
[ ! -e "$tmp/i.npy" ] && ok || bad "a failing gi run wrote i.npy"

# sky-view factors and horizons: --svf-kind normal is the ambient map bit for bit; the horizons
# as (azimuths, rows, columns) .npy, EXR channels named by compass bearing, in ascending bearing
"${gi24[@]}" --cell-size 10 --svf-kind normal --out-svf "$tmp/svf_n.npy" --out-ambient "$tmp/amb.npy" >/dev/null 2>&1 \
  && cmp -s "$tmp/svf_n.npy" "$tmp/amb.npy" && ok || bad "--svf-kind normal differs from --out-ambient"
"${gi24[@]}" --cell-size 10 --reference --svf-kind normal --out-svf "$tmp/svf_rn.npy" --out-ambient "$tmp/amb_r.npy" \
  >/dev/null 2>&1 && cmp -s "$tmp/svf_rn.npy" "$tmp/amb_r.npy" && ok || bad "--reference --svf-kind normal differs"
"${gi24[@]}" --cell-size 10 --out-svf "$tmp/svf_p.npy" >/dev/null 2>&1 && ! cmp -s "$tmp/svf_p.npy" "$tmp/amb.npy" \
  && ok || bad "--svf-kind plain (the default) equals the normal-weighted map"
for ref in "" --reference; do
  "${gi24[@]}" --cell-size 10 $ref --azimuths 8 --out-horizons "$tmp/hz.npy" >/dev/null 2>&1 \
    && head -c 128 "$tmp/hz.npy" | grep -a -q "'shape': (8, 24, 24)" && ok || bad "--out-horizons .npy shape ($ref)"
  "${gi24[@]}" --cell-size 10 $ref --azimuths 8 --out-horizons "$tmp/hz.exr" >/dev/null 2>&1 \
    && [ "$(grep -a -o 'az[0-9]\{3\}_[0-9]\{3\}' "$tmp/hz.exr" | head -8 | tr '\n' ' ')" = \
      "az000_000 az045_000 az090_000 az135_000 az180_000 az225_000 az270_000 az315_000 " ] \
    && ok || bad "--out-horizons .exr channel names ($ref)"
done
# bit-identical for any thread count (a field of several row chunks)
"$T" sim --scene erosion --size 256 --ticks 1 --out "$tmp/hzfield" --format png --quiet >/dev/null 2>&1
hz256=("$T" gi --heightmap "$tmp/hzfield/frame_000001.png" --cell-size 10 --subsample 2 --azimuths 8)
"${hz256[@]}" --threads 1 --out-horizons "$tmp/hz1.npy" --out-svf "$tmp/sv1.npy" >/dev/null 2>&1 \
  && "${hz256[@]}" --threads 3 --out-horizons "$tmp/hz3.npy" --out-svf "$tmp/sv3.npy" >/dev/null 2>&1 \
  && head -c 128 "$tmp/hz1.npy" | grep -a -q "'shape': (8, 256, 256)" \
  && cmp -s "$tmp/hz1.npy" "$tmp/hz3.npy" && cmp -s "$tmp/sv1.npy" "$tmp/sv3.npy" \
  && ok || bad "--out-horizons / --out-svf differ between 1 and 3 threads"
expect_error "horizons of another type" "--out-horizons must end in .npy, .exr or .tif (got '.*h.png')" "${gi24[@]}" \
  --cell-size 10 --out-horizons "$tmp/h.png"
expect_error "bad sky-view kind" "--svf-kind must be plain or normal (got 'cosine')" "${gi24[@]}" --cell-size 10 \
  --svf-kind cosine --out-svf "$tmp/s.npy"
[ ! -e "$tmp/h.png" ] && [ ! -e "$tmp/s.npy" ] && ok || bad "a refused sky-view output was written"

# command-line parse errors: one line and exit 1, like every error; --help still prints help and exits 0
expect_error "unknown flag" "not expected: --bogus" "$T" sim --bogus
expect_error "size that is not a number" "--size" "$T" sim --size abc
expect_error "size past 32 bits" "--size" "$T" sim --size 4294967328
expect_error "no subcommand" "subcommand" "$T"
long=$(printf 'x%.0s' $(seq 1 5000))
expect_error "huge argument" "not expected" "$T" sim "$long"
[ "$(wc -c <"$tmp/e")" -lt 400 ] && ok || bad "a huge argument gives a huge error line"
"$T" sim --help >"$tmp/o" 2>"$tmp/e" && grep -q -- "--scene" "$tmp/o" && ok || bad "sim --help"

# flags and the values they check before anything is read or written
expect_error "negative seed" "--seed must be in" "$T" sim --scene erosion --size 16 --seed -1 --ticks 1
expect_error "dt nan" "--dt must be in" "$T" sim --scene erosion --size 16 --dt nan --ticks 1
expect_error "dt negative" "--dt must be in" "$T" sim --scene erosion --size 16 --dt -1 --ticks 1
expect_error "threads" "--threads must be in" "$T" sim --scene erosion --size 16 --threads 1000 --ticks 1
expect_error "hash every" "--hash-every must be in" "$T" sim --scene erosion --size 16 --hash-every -2 --ticks 1

# a scene file's size, seed and dt apply unless a flag is given (then the flag wins)
"$T" sim --scene "$SRC/scenes/pit-lake.toml" --ticks 0 >"$tmp/o" 2>"$tmp/e" && grep -q "128 x 128 cells of 1 m" "$tmp/o" \
  && [ ! -s "$tmp/e" ] && ok || bad "pit-lake's own size: $(cat "$tmp/o" "$tmp/e")"
"$T" sim --scene "$SRC/scenes/pit-lake.toml" --ticks 0 --size 64 >"$tmp/o" 2>&1 && grep -q "64 x 64 cells of 2 m" "$tmp/o" \
  && ok || bad "--size over pit-lake: $(cat "$tmp/o")"
printf 'base = "erosion"\nsize = [30, 20]\nseed = 4\ndt = 0.125\n' >"$tmp/s4.toml"
printf 'base = "erosion"\nsize = [30, 20]\nseed = 5\ndt = 0.125\n' >"$tmp/s5.toml"
"$T" sim --scene "$tmp/s4.toml" --ticks 0 >"$tmp/o" 2>&1 && grep -q "30 x 20 cells of .* dt 0.125 s" "$tmp/o" && ok \
  || bad "scene size and dt: $(cat "$tmp/o")"
"$T" sim --scene "$tmp/s4.toml" --ticks 0 --dt 0.25 >"$tmp/o" 2>&1 && grep -q "dt 0.25 s" "$tmp/o" && ok || bad "--dt over the scene: $(cat "$tmp/o")"
h4=$("$T" sim --scene "$tmp/s4.toml" --ticks 1 --hash-every 1 --quiet)
h5=$("$T" sim --scene "$tmp/s5.toml" --ticks 1 --hash-every 1 --quiet)
h54=$("$T" sim --scene "$tmp/s5.toml" --ticks 1 --hash-every 1 --quiet --seed 4)
[ -n "$h4" ] && [ "$h4" != "$h5" ] && ok || bad "scene seeds 4 and 5 give the same hash"
[ "$h54" = "$h4" ] && ok || bad "--seed 4 over the seed-5 scene differs from the seed-4 scene"

# scene values out of their physical range: one line naming the key; no output folder made
scene_error() {  # description, pattern, scene text
  printf "$3" >"$tmp/bad.toml"
  rm -rf "$tmp/never"
  expect_error "$1" "$2" "$T" sim --scene "$tmp/bad.toml" --ticks 2 --out "$tmp/never"
  [ ! -e "$tmp/never" ] && ok || bad "$1: the output folder was made"
}
scene_error "huge rain" "'hydraulic.rain_rate' must be in \[0, 0.01\] (got 1e+30)" 'base = "erosion"\n[hydraulic]\nrain_rate = 1e30\n'
scene_error "negative gravity" "'hydraulic.gravity'" 'base = "erosion"\nsize = 16\n[hydraulic]\ngravity = -9.81\n'
scene_error "negative dry depth" "'waves.dry_depth'" 'base = "waves"\n[waves]\ndry_depth = -1.0\n'
scene_error "negative soil" "'soil_depth'" 'base = "erosion"\nsoil_depth = -5.0\n'
scene_error "nan dt" "'dt' must be a finite number" 'base = "erosion"\ndt = nan\n'
scene_error "size past 32 bits" "'size' must be in \[1, 16384\] (got 4294967328)" 'base = "erosion"\nsize = 4294967328\n'
scene_error "seed below 0" "'seed'" 'base = "erosion"\nseed = -3\n'
scene_error "change tile overflow" "'change_tile'" 'base = "erosion"\nchange_tile = 2147483647\n'
scene_error "dem without a file" "'terrain.file' is missing" 'size = 16\n[terrain]\nkind = "dem"\n'
scene_error "empty scene file" "sets nothing" ''
mkdir -p "$tmp/folder.toml"
expect_error "a folder as the scene" "is not a file" "$T" sim --scene "$tmp/folder.toml" --ticks 1

# hostile inputs: one short error line, quickly (unit tests: tests/test_io_bad_input.cpp)
expect_short_error() {  # description, pattern, command...
  local what=$1 pattern=$2
  shift 2
  timeout 60 "$@" >"$tmp/o" 2>"$tmp/e"
  local rc=$?
  if [ $rc = 1 ] && [ "$(wc -l <"$tmp/e")" = 1 ] && [ "$(wc -c <"$tmp/e")" -le 400 ] && grep -q -- "$pattern" "$tmp/e"; then ok
  else bad "$what: rc=$rc stderr=$(head -c 600 "$tmp/e")"; fi
}
vdb="$tmp/frames/frame_000000.vdb"
head -c 8192 "$vdb" >"$tmp/cut.vdb"
expect_short_error "truncated VDB heightmap" "cut.vdb: truncated: grid 'height' ends at byte" "$T" gi --heightmap "$tmp/cut.vdb" --cell-size 10
cp "$vdb" "$tmp/grids.vdb"
printf '\377\377\377\177' | dd of="$tmp/grids.vdb" bs=1 seek=61 conv=notrunc 2>/dev/null
expect_short_error "VDB declaring 2^31 grids" "2147483647 grids" "$T" gi --heightmap "$tmp/grids.vdb" --cell-size 10
cp "$vdb" "$tmp/mutant.vdb"
# two bytes in the middle of the bedrock grid (the layer a heightmap reads),
# which lies between its name and the next grid's
bedrock_at=$(grep -abo bedrock "$vdb" | tail -1 | cut -d: -f1)
soil_at=$(grep -abo soil "$vdb" | head -1 | cut -d: -f1)
printf '\377\377' | dd of="$tmp/mutant.vdb" bs=1 seek=$(( (bedrock_at + soil_at) / 2 )) conv=notrunc 2>/dev/null
expect_short_error "damaged VDB heightmap" "mutant.vdb" "$T" gi --heightmap "$tmp/mutant.vdb" --cell-size 10
: >"$tmp/empty.png"
expect_short_error "empty heightmap file" "empty.png: not a PNG file" "$T" gi --heightmap "$tmp/empty.png" --cell-size 10
echo "1 2 3" >"$tmp/heights.txt"
expect_short_error "heightmap of another format" "unknown heightmap format '.txt'" "$T" gi --heightmap "$tmp/heights.txt" --cell-size 10
expect_short_error "output onto a device" "must end in .npy, .exr or .tif" "$T" gi --heightmap "$hm24" --cell-size 10 --out-ambient /dev/full
# a 68-byte PNG declaring 60000 x 60000 pixels; a 1 x 1 PNG; an 8-bit grey PNG
echo 'iVBORw0KGgoAAAANSUhEUgAA6mAAAOpgEAAAAAD1KfbdAAAAC0lEQVR4nGNggAAAAAgAAbdYc5UAAAAASUVORK5CYII=' | base64 -d >"$tmp/huge.png"
expect_short_error "PNG declaring 60000 x 60000" "60000 x 60000 pixels" "$T" gi --heightmap "$tmp/huge.png" --cell-size 10
echo 'iVBORw0KGgoAAAANSUhEUgAAAAEAAAABEAAAAABq7kcWAAAAC0lEQVR4nGMQMgEAAFsAR5b7G2UAAAAASUVORK5CYII=' | base64 -d >"$tmp/one.png"
expect_short_error "1 x 1 heightmap" "at least 2 x 2" "$T" gi --heightmap "$tmp/one.png" --cell-size 10
echo 'iVBORw0KGgoAAAANSUhEUgAAAAQAAAAECAAAAACMmsGiAAAAHElEQVR4nGNgsKnYwsDl1rSPQSSg5wSDXNS0SwA5HAaR4OH8SgAAAABJRU5ErkJggg==' | base64 -d >"$tmp/grey8.png"
"$T" gi --heightmap "$tmp/grey8.png" --cell-size 10 --out-ambient "$tmp/grey8.npy" >/dev/null 2>"$tmp/e" && [ -s "$tmp/grey8.npy" ] \
  && [ "$(grep -c 'warning: .*8-bit PNG' "$tmp/e")" = 1 ] && ok || bad "8-bit PNG heightmap: $(cat "$tmp/e")"
printf '#?RADIANCE\nFORMAT=32-bit_rle_rgbe\n\n-Y 4 +X 30000\n' >"$tmp/wide.hdr"
expect_short_error "HDR declaring 30000 pixels wide" "30000 x 4 pixels" "$T" gi --heightmap "$hm24" --cell-size 10 --light "$tmp/wide.hdr"
mkdir -p "$tmp/fdir/frame_000000.vdb"
expect_short_error "frame path is a folder" "frame_000000.vdb: cannot move" "$T" sim --scene erosion --size 16 --ticks 1 \
  --out "$tmp/fdir" --format vdb --quiet
[ -d "$tmp/fdir/frame_000000.vdb" ] && [ "$(ls -A "$tmp/fdir" | wc -l)" = 1 ] && ok || bad "frame path is a folder: $(ls "$tmp/fdir")"
# a full disk (a file size limit): the run fails naming the frame, and the
# frames already in the folder keep their bytes, with no temporary left
"$T" sim --scene erosion --size 40 --ticks 1 --out "$tmp/full" --format both --quiet >/dev/null 2>&1
cp -r "$tmp/full" "$tmp/full_before"
for fmt in vdb png; do
  (trap '' XFSZ; ulimit -f 1; "$T" sim --scene erosion --size 40 --ticks 1 --seed 9 --out "$tmp/full" --format $fmt --quiet) \
    >/dev/null 2>"$tmp/e"
  rc=$?
  if [ $rc = 1 ] && [ "$(wc -l <"$tmp/e")" = 1 ] && grep -q "frame_000000.$fmt: .*write failed.*File too large" "$tmp/e"; then ok
  else bad "full disk ($fmt): rc=$rc $(cat "$tmp/e")"; fi
done
diff -r "$tmp/full_before" "$tmp/full" >/dev/null && ok || bad "a failed write changed the frames or left files behind"

# GeoTIFF: heights and cell size from the file, outputs that carry its place
source "$SRC/tests/hand_geotiff.sh"
hand_geotiff "$tmp/dem.tif" 24 20 utm32n
hand_geotiff "$tmp/holes.tif" 24 20 utm32n -9999
hand_geotiff "$tmp/wgs84.tif" 24 20 wgs84
"$T" gi --heightmap "$tmp/dem.tif" --out-ambient "$tmp/dem_ambient.tif" --out-shade "$tmp/dem_shade.tif" >"$tmp/o" 2>"$tmp/e" \
  && grep -q "24 x 20 cells of 30 m" "$tmp/o" && [ ! -s "$tmp/e" ] && ok || bad "gi on a GeoTIFF: $(cat "$tmp/o" "$tmp/e")"
# an output read back as a heightmap: still georeferenced, same size and cell
"$T" gi --heightmap "$tmp/dem_ambient.tif" --out-ambient "$tmp/again.npy" 2>&1 | grep -q "24 x 20 cells of 30 m" \
  && ok || bad "a GeoTIFF output keeps the input's georeferencing"
# --cell-size overrides the file's own
"$T" gi --heightmap "$tmp/dem.tif" --cell-size 12 --out-ambient "$tmp/dem12.npy" 2>&1 | grep -q "cells of 12 m" \
  && ok || bad "--cell-size over a GeoTIFF"
"$T" gi --heightmap "$tmp/holes.tif" --out-ambient "$tmp/holes.npy" >/dev/null 2>"$tmp/e" \
  && [ "$(grep -c 'warning: .*holes.tif: 20 nodata cells filled with the nearest valid height' "$tmp/e")" = 1 ] \
  && ok || bad "GeoTIFF nodata: $(cat "$tmp/e")"
expect_error "--z-scale with a GeoTIFF" "z-scale and --z-offset apply to PNG" "$T" gi --heightmap "$tmp/dem.tif" --z-scale 2
expect_error "GeoTIFF in degrees" "wgs84.tif: has a geographic CRS in degrees.*gdalwarp" "$T" gi --heightmap "$tmp/wgs84.tif"
head -c 300 "$tmp/dem.tif" >"$tmp/cut.tif"
expect_error "truncated GeoTIFF" "cut.tif: " "$T" gi --heightmap "$tmp/cut.tif"
printf 'II*\x00garbage' >"$tmp/garbage.tif"
expect_error "garbage GeoTIFF" "garbage.tif: not a readable GeoTIFF" "$T" gi --heightmap "$tmp/garbage.tif"
# a scene from the GeoTIFF: its cell size, and frames that overlay it
printf 'base = "dem"\n[terrain]\nfile = "dem.tif"\nresample = false\n' >"$tmp/dem.toml"
"$T" sim --scene "$tmp/dem.toml" --ticks 1 --out "$tmp/demframes" --format tif >"$tmp/o" 2>&1 \
  && grep -q "24 x 20 cells of 30 m" "$tmp/o" && ok || bad "sim on a GeoTIFF scene: $(cat "$tmp/o")"
"$T" gi --heightmap "$tmp/demframes/frame_000001.tif" --out-ambient "$tmp/f.npy" 2>&1 | grep -q "24 x 20 cells of 30 m" \
  && ok || bad "sim's GeoTIFF frames keep the DEM's georeferencing"
# a failed GeoTIFF write keeps the earlier file, and leaves no temporary
cp "$tmp/dem_ambient.tif" "$tmp/dem_ambient_before.tif"
(trap '' XFSZ; ulimit -f 1; "$T" gi --heightmap "$tmp/dem.tif" --out-ambient "$tmp/dem_ambient.tif" --light sunsky) \
  >/dev/null 2>"$tmp/e"
rc=$?
[ $rc = 1 ] && [ "$(wc -l <"$tmp/e")" = 1 ] && grep -q "dem_ambient.tif: " "$tmp/e" && ok || bad "full disk (tif): rc=$rc $(cat "$tmp/e")"
cmp -s "$tmp/dem_ambient.tif" "$tmp/dem_ambient_before.tif" && ok || bad "a failed GeoTIFF write changed the file"
# horizons of a GeoTIFF: one band per azimuth, described by its bearing clockwise from north, with
# the input's place (read back as a heightmap: band 1, bearing 0, north)
"$T" gi --heightmap "$tmp/dem.tif" --azimuths 4 --out-horizons "$tmp/dem_hz.tif" >/dev/null 2>&1 \
  && [ "$(grep -a -o 'role="description">[0-9.]*<' "$tmp/dem_hz.tif" | tr '\n' ' ')" = \
    'role="description">0< role="description">90< role="description">180< role="description">270< ' ] \
  && "$T" gi --heightmap "$tmp/dem_hz.tif" --out-ambient "$tmp/hz_again.npy" 2>&1 | grep -q "24 x 20 cells of 30 m" \
  && ok || bad "--out-horizons .tif bands and georeferencing"
ls "$tmp" | grep -q 'dem_ambient.tif.*tmp\|tmp.*dem_ambient' && bad "GeoTIFF temporary left behind" || ok

# EXR frames: every layer a float32 channel; a frame is a heightmap again
# (its height channel and cell size); the GI maps as channels of one EXR
"$T" sim --scene erosion --size 24 --ticks 3 --out "$tmp/exrframes" --format exr --quiet \
  && [ "$(ls "$tmp/exrframes"/*.exr | wc -l)" = 2 ] && ok || bad "sim --format exr"
"$T" gi --heightmap "$tmp/exrframes/frame_000003.exr" --out-exr "$tmp/gi.exr" --bounces 1 >"$tmp/o" 2>&1 \
  && grep -q "24 x 24 cells of" "$tmp/o" && [ -s "$tmp/gi.exr" ] && ok || bad "gi on an EXR frame: $(cat "$tmp/o")"
"$T" gi --heightmap "$tmp/gi.exr" --out-ambient "$tmp/gi_again.npy" >/dev/null 2>&1 && ok || bad "a gi --out-exr file is a heightmap"
expect_error "--out-exr of another type" "--out-exr must end in .exr" "$T" gi --heightmap "$tmp/dem.tif" --out-exr "$tmp/x.png"
expect_error "--z-scale with an EXR" "an EXR's heights are used as stored" "$T" gi --heightmap "$tmp/gi.exr" --z-scale 2
head -c 600 "$tmp/exrframes/frame_000003.exr" >"$tmp/cut.exr"
expect_short_error "truncated EXR heightmap" "cut.exr: " "$T" gi --heightmap "$tmp/cut.exr" --cell-size 10

echo "cli: $pass passed, $fail failed"
[ $fail -eq 0 ]
