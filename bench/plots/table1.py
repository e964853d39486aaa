"""table1.png / .svg from table1.csv (terrain_bench table1): frame time and
GI memory against the grid size, ours beside the paper's GTX 285, one line
per sub-sampling (one bounce)."""

import plot_common as pc

COLOURS = {1: "tab:blue", 2: "tab:orange", 4: "tab:green"}


def series(rows, s, key):
    pts = [(int(r["size"]), float(r[key])) for r in rows
           if int(r["subsample"]) == s and int(r["bounces"]) == 1 and r[key]]
    return [p[0] for p in pts], [p[1] for p in pts]


def quartile_bars(rows, s, ours, y, quartiles):
    """Distances from each median down to its first and up to its third quartile."""
    if not quartiles or quartiles[0] not in rows[0]:
        return None
    _, q1 = series(rows, s, quartiles[0])
    _, q3 = series(rows, s, quartiles[1])
    return [[m - a for m, a in zip(y, q1)], [b - m for m, b in zip(y, q3)]]


def panel(ax, rows, ours, paper, ylabel, title, quartiles=None):
    for s in sorted({int(r["subsample"]) for r in rows}):
        x, y = series(rows, s, ours)
        ax.errorbar(x, y, yerr=quartile_bars(rows, s, ours, y, quartiles), fmt="o-", capsize=3,
                    color=COLOURS.get(s, "k"), label=f"{s}x, this engine (2 CPU threads)")
        px, py = series(rows, s, paper)
        if px:
            ax.plot(px, py, "s--", color=COLOURS.get(s, "k"), alpha=0.6, label=f"{s}x, paper (GTX 285)")
    ax.set_xscale("log", base=2)
    ax.set_yscale("log")
    pc.plain_log_ticks(ax.yaxis)
    ax.set_xlabel("grid side (cells)")
    ax.set_ylabel(ylabel)
    ax.set_title(title)
    sizes = sorted({int(r["size"]) for r in rows})
    ax.set_xticks(sizes, [f"{n}²" for n in sizes])
    ax.minorticks_off()
    ax.legend()


def main():
    folder = pc.results_dir(__doc__)
    rows = pc.read_csv(folder, "table1.csv")
    fig, grid = pc.figure_grid(1, 2, 12.5, 5)
    axes = grid[0]
    panel(axes[0], rows, "ms", "paper_ms", "ms per frame (one bounce; bars: quartiles)", "GI frame time",
          ("ms_q1", "ms_q3"))
    panel(axes[1], rows, "memory_mb", "paper_memory_mb", "MB", "GI memory")
    pc.save(fig, folder, "table1")


if __name__ == "__main__":
    main()
