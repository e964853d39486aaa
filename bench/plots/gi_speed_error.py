#!/usr/bin/env python3
"""gi_speed_error.png / .svg from gi_timing.csv (`terrain_bench gi timing`):
ambient RMSE against the ground truth over the time of a GI frame with 2
threads, one line per DEM size and settings through 4x -> 2x -> 1x
sub-sampling, with the 15 ms frame target."""

import plot_common as pc

SIZE_COLOURS = {256: "tab:red", 512: "tab:blue", 1024: "tab:green"}
STYLES = {  # settings -> marker, line width, label
    "paper": ("s", 1.0, "paper settings"),
    "engine": ("o", 2.2, "engine defaults"),
}
TARGET_MS = 15.0


def main():
    folder = pc.results_dir(__doc__)
    rows = [r for r in pc.read_csv(folder, "gi_timing.csv") if int(r["threads"]) == 2]
    fig, ax = pc.figure(8.0, 5.2)
    for size, colour in SIZE_COLOURS.items():
        for settings, (marker, width, label) in STYLES.items():
            line = [r for r in rows if int(r["size"]) == size and r["settings"] == settings]
            line.sort(key=lambda r: -int(r["subsample"]))  # 4x -> 2x -> 1x
            if not line:
                continue
            ms = [float(r["ms"]) for r in line]
            err = [float(r["rmse"]) for r in line]
            ax.plot(ms, err, marker=marker, lw=width, ms=6, color=colour, label=f"{size}² {label}")
            for r, x, y in zip(line, ms, err):
                ax.annotate(f"{r['subsample']}x", (x, y), xytext=(5, 4), textcoords="offset points",
                            fontsize=9, color=colour)
    ax.axvline(TARGET_MS, color="0.45", lw=1.0, ls="--")
    ax.text(TARGET_MS * 1.04, 0.98, f"{TARGET_MS:g} ms target", transform=ax.get_xaxis_transform(),
            va="top", fontsize=9, color="0.35")
    ax.set_xscale("log")
    pc.plain_log_ticks(ax.xaxis)
    ax.set_ylim(bottom=0.0)
    ax.set_xlabel("GI frame time (ms, 2 threads, log scale)")
    ax.set_ylabel("ambient RMSE against the ground truth")
    ax.set_title("GI frame: speed against error (sub-sampling 4x → 2x → 1x)")
    ax.legend(loc="upper right", ncols=1)
    pc.save(fig, folder, "gi_speed_error")


if __name__ == "__main__":
    main()
