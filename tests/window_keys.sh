#!/usr/bin/env bash
# Runs inside xvfb-run (render_cli_test.sh): opens the demo window, sends it
# real key presses through XTEST (xdotool) and lets it run out its frames.
# Usage: window_keys.sh path/to/terrain out_folder log_file
T=$1
out=$2
log=$3
"$T" demo --scene erosion --size 32 --width 320 --height 200 --frames 300 --out "$out" >"$log" 2>&1 &
pid=$!
wid=""
for _ in $(seq 100); do
  wid=$(xdotool search --name "terrain demo" 2>/dev/null | head -1)
  [ -n "$wid" ] && break
  sleep 0.1
done
[ -n "$wid" ] || { kill "$pid"; echo "window_keys: no window" >>"$log"; exit 1; }
xdotool mousemove --window "$wid" 160 100   # X gives the keys to the window under the pointer
sleep 0.5
for key in p space F12 r h p; do
  xdotool key "$key"
  sleep 0.4
done
wait "$pid"
