#!/usr/bin/env python3
"""scaling.png / .svg from scaling.csv and scaling_fit.csv (`terrain_bench
scaling`): GI frame time against the number of cells (left) and against the
number of azimuths (right), at each thread count, log-log, with the fitted
power laws and an ideal linear reference."""

import plot_common as pc

THREAD_COLOURS = {1: "tab:blue", 2: "tab:red", 4: "tab:green", 8: "tab:purple"}
AZIMUTH_SWEEPS = {  # sweep -> marker, label
    "env_azimuths": ("o", "environment m"),
    "indirect_azimuths": ("s", "indirect scan"),
}


def colour(threads):
    return THREAD_COLOURS.get(threads, "tab:gray")


def fits_by_key(folder):
    return {(f["sweep"], int(f["threads"])): f for f in pc.read_csv(folder, "scaling_fit.csv")}


def fitted_line(ax, fit, col, label):
    """The fitted power law over the x range it was fitted on."""
    lo, hi = float(fit["x_from"]), float(fit["x_to"])
    p, a = float(fit["exponent"]), float(fit["prefactor_ms"])
    ax.plot([lo, hi], [a * lo ** p, a * hi ** p], ls="--", lw=1.2, color=col, label=label)


def cells_panel(ax, rows, fits):
    rows = [r for r in rows if r["sweep"] == "cells"]
    threads = sorted({int(r["threads"]) for r in rows})
    for t in threads:
        line = sorted((r for r in rows if int(r["threads"]) == t), key=lambda r: float(r["cells"]))
        xs = [float(r["cells"]) for r in line]
        ys = [float(r["ms"]) for r in line]
        bars = None
        if line and "ms_q1" in line[0]:  # the quartiles of the frames around each median
            bars = [[y - float(r["ms_q1"]) for r, y in zip(line, ys)], [float(r["ms_q3"]) - y for r, y in zip(line, ys)]]
        ax.errorbar(xs, ys, yerr=bars, marker="o", lw=0, elinewidth=1.2, capsize=3, ms=7, color=colour(t),
                    label=f"{t} thread{'s' if t > 1 else ''}")
        for r, x, y in zip(line, xs, ys) if t == threads[0] else []:  # the sizes, once
            ax.annotate(f"{r['size']}²", (x, y), xytext=(-6, 6), textcoords="offset points", fontsize=8,
                        color="0.3", ha="right")
        fit = fits.get(("cells", t))
        if fit and int(fit["points"]) >= 2:
            fitted_line(ax, fit, colour(t), f"fit, {t}T: time $\\propto$ cells$^{{{float(fit['exponent']):.2f}}}$")
    # ideal linear scaling through the first fitted point of the fewest threads
    fit = fits.get(("cells", threads[0])) if threads else None
    if fit and int(fit["points"]) >= 2:
        base = [r for r in rows if int(r["threads"]) == threads[0] and float(r["cells"]) == float(fit["x_from"])][0]
        x0, y0 = float(base["cells"]), float(base["ms"])
        x1 = max(float(r["cells"]) for r in rows)
        ax.plot([x0, x1], [y0, y0 * x1 / x0], color="0.5", lw=1.0, ls=":", label="linear: time $\\propto$ cells")
    ax.set_xscale("log")
    ax.set_yscale("log")
    pc.plain_log_ticks(ax.yaxis)
    ax.set_xlabel("cells (log scale)")
    ax.set_ylabel("GI frame time (ms, log scale)")
    ax.set_title("against cells")
    ax.legend(loc="upper left")


def azimuths_panel(ax, rows, fits):
    for sweep, (marker, name) in AZIMUTH_SWEEPS.items():
        sel = [r for r in rows if r["sweep"] == sweep]
        for t in sorted({int(r["threads"]) for r in sel}):
            line = sorted((r for r in sel if int(r["threads"]) == t), key=lambda r: int(r[sweep]))
            xs = [int(r[sweep]) for r in line]
            ys = [float(r["ms"]) for r in line]
            fit = fits.get((sweep, t))
            exp = f", $\\propto$ az$^{{{float(fit['exponent']):.2f}}}$" if fit and int(fit["points"]) >= 2 else ""
            ax.plot(xs, ys, marker=marker, lw=1.5, ms=7, color=colour(t), ls="-" if sweep == "env_azimuths" else "--",
                    label=f"{name}, {t}T{exp}")
    size = next((r["size"] for r in rows if r["sweep"] in AZIMUTH_SWEEPS), "?")
    ax.set_xscale("log", base=2)
    ax.set_yscale("log")
    ax.xaxis.set_major_formatter(pc.ticker.FuncFormatter(lambda v, _pos: f"{v:g}"))
    pc.plain_log_ticks(ax.yaxis, subs=(2.0, 3.0, 5.0, 7.0))
    ax.set_xlabel("azimuths of the swept scan (log scale)")
    ax.set_ylabel("GI frame time (ms, log scale)")
    ax.set_title(f"against azimuths ({size}²)")
    ax.legend(loc="upper left")


def main():
    folder = pc.results_dir(__doc__)
    rows = pc.read_csv(folder, "scaling.csv")
    fits = fits_by_key(folder)
    fig, grid = pc.figure_grid(1, 2, 13.0, 5.4)
    left, right = grid[0]
    cells_panel(left, rows, fits)
    azimuths_panel(right, rows, fits)
    sub = rows[0]["subsample"] if rows else "?"
    fig.suptitle(f"Whole GI frame (engine defaults, one bounce, {sub}x): time against cells and azimuths")
    pc.save(fig, folder, "scaling")


if __name__ == "__main__":
    main()
