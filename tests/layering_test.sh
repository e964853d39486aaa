#!/usr/bin/env bash
# The libraries are layered, every include pointing down:
#   core -> sim -> gi -> engine -> render -> app   (sim and gi are side by side)
# the Python module (python/) beside app, on the libraries below render
# and the OpenGL code sees only what it uploads (engine/frame_data.h) and the
# plain light types of gi/. Fails naming each include that runs against it.
# Usage: layering_test.sh SOURCE_DIR
set -uo pipefail
cd "$1"
fail=0
# allowed: the folders each folder's files may include from
declare -A allowed=(
  [core]="core"
  [sim]="core sim"
  [gi]="core gi"
  [engine]="core sim gi engine"
  [render]="core gi engine render"
  [app]="core sim gi engine render app"
  [python]="core sim gi engine app python"
)
for dir in "${!allowed[@]}"; do
  for f in "$dir"/*.h "$dir"/*.cpp; do
    [ -e "$f" ] || continue
    while IFS= read -r inc; do
      top=${inc%%/*}
      case " ${allowed[$dir]} " in *" $top "*) ;; *)
        case "$top" in core|sim|gi|engine|render|app|python) echo "layering: $f includes $inc"; fail=1 ;; esac ;;
      esac
      if [ "$dir" = render ]; then
        case "$inc" in gi/*|engine/*)
          case "$inc" in engine/frame_data.h|gi/lights.h|gi/sh.h) ;; *) echo "layering: $f includes $inc (render sees FrameData only)"; fail=1 ;; esac ;;
        esac
      fi
    done < <(sed -n 's/^#include "\([^"]*\)".*/\1/p' "$f")
  done
done
# terrain sim and terrain gi (and the library the Python module shares with
# the latter) build without GL headers
for f in app/cmd_sim.cpp app/cmd_gi.cpp app/commands.h app/gi_options.* app/gi_run.* app/gi_images.* \
  app/light_options.* app/progress.*; do
  if grep -qE '#include [<"](render/|GL/|GLFW/)' "$f"; then echo "layering: $f includes GL or render headers"; fail=1; fi
done
if [ $fail -eq 0 ]; then echo "layering: every include points down"; fi
exit $fail
