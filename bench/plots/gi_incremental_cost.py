#!/usr/bin/env python3
"""gi_incremental_cost.png / .svg from gi_incremental.csv (`terrain_bench
gi-incremental`): GI time of an incremental frame over a full frame's of the
same surface against the share of the cells that changed (the sweep of
square pits, the rows with a changed_area), one line per tolerance."""

import plot_common as pc

COLOURS = ["tab:red", "tab:blue", "tab:green", "tab:purple", "tab:orange"]


def main():
    folder = pc.results_dir(__doc__)
    rows = [r for r in pc.read_csv(folder, "gi_incremental.csv") if r.get("changed_area")]
    tolerances = sorted({float(r["tolerance"]) for r in rows})
    fig, ax = pc.figure()
    for k, tol in enumerate(tolerances):
        line = sorted((r for r in rows if float(r["tolerance"]) == tol), key=lambda r: float(r["changed_area"]))
        share = [100.0 * float(r["changed_area"]) for r in line]
        ratio = [100.0 * float(r["incremental_ms"]) / float(r["full_ms"]) for r in line]
        ax.plot(share, ratio, marker="o", lw=2.0, color=COLOURS[k % len(COLOURS)],
                label=f"tolerance {tol:g}" + (" (exact: every receiver)" if tol == 0 else ""))
    ax.axhline(100.0, color="0.45", lw=1.0, ls="--")
    ax.text(0.01, 101.5, "full frame", transform=ax.get_yaxis_transform(), fontsize=9, color="0.35")
    ax.set_xscale("log")
    pc.plain_log_ticks(ax.xaxis)
    ax.set_ylim(0.0, 120.0)
    ax.set_xlabel("cells changed (% of the 512² DEM, log scale)")
    ax.set_ylabel("incremental GI time (% of a full frame)")
    ax.set_title("Incremental GI frames: cost against the changed area")
    ax.legend(loc="lower right")
    pc.save(fig, folder, "gi_incremental_cost")


if __name__ == "__main__":
    main()
