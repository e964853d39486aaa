#!/usr/bin/env python3
"""Instruction profile of one GI frame (callgrind), written to
bench/results/profile_<n>_2x.md.

Runs `terrain_bench gi-indirect --probe N` (an N^2 erosion frame, 2x, one
bounce, sun-and-sky + one key light: the Table 1 frame) under callgrind twice,
with 2 and with 4 timed frames after the warm-up, collecting only inside
runGiFrame; the difference of the two runs is the cost of two frames, free of
the first frame's allocations and of everything outside the frame. One
thread: collection follows the calling thread's stack, so work handed to
other threads would not be counted (and would be counted by chance). Reports
instructions per frame by function (inlined kernels folded into the function
they were inlined into where callgrind names the source line instead).

Usage: bench/profile_frame.py BUILD_DIR [--size N] [--out DIR]
BUILD_DIR: a Release build with debug information, e.g.
  cmake -S . -B build-prof -DCMAKE_BUILD_TYPE=Release -DCMAKE_CXX_FLAGS_RELEASE="-O3 -g -DNDEBUG"
  cmake --build build-prof --target terrain_bench
Needs valgrind (Debian: valgrind). Takes a few minutes at 512^2.
"""

import argparse
import os
import re
import subprocess
import sys
import tempfile


def callgrind(bench, size, runs, folder):
    out = os.path.join(folder, f"cg.{runs}")
    cmd = ["valgrind", "--tool=callgrind", f"--callgrind-out-file={out}",
           "--toggle-collect=terrain::gi::runGiFrame*", bench, "gi-indirect", "--probe", str(size), "--runs",
           str(runs), "--probe-threads", "1"]
    print(f"profile: {' '.join(cmd)}", file=sys.stderr)
    subprocess.run(cmd, check=True, stdout=subprocess.DEVNULL, stderr=subprocess.DEVNULL)
    text = subprocess.run(["callgrind_annotate", "--threshold=100", "--auto=no", "--inclusive=no", out], check=True,
                          capture_output=True, text=True).stdout
    costs = {}
    for line in text.splitlines():
        # "cost (share)  file:function [binary]", self cost per function
        m = re.match(r"\s*([\d,]+)\s+\(\s*[\d.]+%\)\s+(.*)", line)
        if m:
            costs[m.group(2).strip()] = costs.get(m.group(2).strip(), 0) + int(m.group(1).replace(",", ""))
    return costs


def function_of(entry):
    """The engine function an entry belongs to: its name, or for a source line
    callgrind reports on its own (an inlined template), the file it is in."""
    if "memset" in entry or "memcpy" in entry or "memmove" in entry:
        return "libc memset / memcpy"
    # the first engine function named that is not the parallel loop (a loop
    # body is charged to the function it belongs to)
    for name in re.findall(r"terrain::(?:gi::)?(?:\(anonymous namespace\)::)?([A-Za-z0-9_]+)", entry):
        if name not in ("parallelFor", "parallelForRows", "gi", "Grid", "ConstGridView"):
            return name
    m = re.search(r"/(?:gi|core)/([a-z_]+\.[ch](?:pp)?)", entry)
    return f"inlined code in {m.group(1)}" if m else "other (TBB, libm, ...)"


def main():
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("build", help="build folder with terrain_bench (Release with -g)")
    parser.add_argument("--size", type=int, default=512)
    parser.add_argument("--out", default=os.path.join(os.path.dirname(os.path.abspath(__file__)), "results"))
    args = parser.parse_args()
    bench = os.path.join(args.build, "terrain_bench")
    with tempfile.TemporaryDirectory() as folder:
        two, four = callgrind(bench, args.size, 2, folder), callgrind(bench, args.size, 4, folder)
    frame = (four["PROGRAM TOTALS"] - two["PROGRAM TOTALS"]) / 2
    by_function = {}
    for entry, cost in four.items():
        if entry == "PROGRAM TOTALS" or entry.startswith("events"):
            continue
        name = function_of(entry)
        by_function[name] = by_function.get(name, 0) + (cost - two.get(entry, 0)) / 2
    rows = sorted(by_function.items(), key=lambda kv: -kv[1])
    md = [f"# Instruction profile of one GI frame, {args.size}^2 2x, one bounce\n",
          f"Command: `bench/profile_frame.py BUILD --size {args.size}` (callgrind over `terrain_bench gi-indirect "
          f"--probe {args.size} --probe-threads 1`, the Table 1 frame: erosion ground, sun-and-sky + one key light, engine "
          "defaults; the difference of a 4-frame and a 2-frame run, so one frame after the first, inside "
          "runGiFrame only). Instructions are not time (cache misses and divisions cost more than one "
          "instruction), but they say where the work is and do not depend on the machine's load.\n",
          f"Instructions per frame: **{frame / 1e6:.0f} M**.\n",
          "| function | M instructions / frame | share |", "|---|---|---|"]
    shown = 0.0
    for name, cost in rows[:25]:
        md.append(f"| {name} | {cost / 1e6:.1f} | {100 * cost / frame:.1f} % |")
        shown += cost
    md.append(f"| (the rest) | {(frame - shown) / 1e6:.1f} | {100 * (frame - shown) / frame:.1f} % |")
    path = os.path.join(args.out, f"profile_{args.size}_2x.md")
    with open(path, "w") as f:
        f.write("\n".join(md) + "\n")
    print(f"wrote {path}", file=sys.stderr)


if __name__ == "__main__":
    main()
