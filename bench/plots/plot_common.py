"""What every plot of bench/plots shares: the command line, reading a
suite's CSV, one look (readable fonts, grids, legends) and writing the
figure as PNG and SVG beside the CSV it was drawn from.

Each plot is a script `bench/plots/<name>.py RESULTS_DIR`: build/terrain_bench
runs it after writing the CSV, and it can be run by hand to redraw.
"""

import argparse
import csv
import os
import sys

import matplotlib

matplotlib.use("Agg")  # files only: no display needed
import matplotlib.pyplot as plt  # noqa: E402 (after the backend is chosen)
import matplotlib.ticker as ticker  # noqa: E402


def results_dir(description):
    """The results folder named on the command line."""
    parser = argparse.ArgumentParser(description=description)
    parser.add_argument("results", help="folder with the suite's CSV; the plot is written there")
    return parser.parse_args().results


def read_csv(folder, name):
    """The rows of folder/name as dicts of strings; exits with one line when it is missing."""
    path = os.path.join(folder, name)
    try:
        with open(path, newline="") as f:
            return list(csv.DictReader(f))
    except OSError as e:
        sys.exit(f"{os.path.basename(sys.argv[0])}: cannot read {path}: {e.strerror}")


def figure(width=7.5, height=4.8):
    """A new figure and axes in the house style."""
    fig, axes = figure_grid(1, 1, width, height)
    return fig, axes[0][0]


def figure_grid(rows, cols, width=7.5, height=4.8, **subplots_args):
    """A new figure of rows x cols panels in the house style; axes[row][col]."""
    plt.rcParams.update({
        "font.size": 11,
        "axes.titlesize": 12,
        "axes.labelsize": 11,
        "legend.fontsize": 9,
        "svg.fonttype": "none",  # text stays text in the SVG
        "svg.hashsalt": "terrain",  # the same SVG for the same data
    })
    fig, axes = plt.subplots(rows, cols, figsize=(width, height), layout="constrained", squeeze=False,
                             **subplots_args)
    for ax in axes.flat:
        ax.grid(True, which="major", alpha=0.35)
        ax.grid(True, which="minor", alpha=0.12)
    return fig, axes


def save(fig, folder, stem):
    """Writes folder/stem.png and folder/stem.svg and says so on stderr."""
    for ext in ("png", "svg"):
        path = os.path.join(folder, f"{stem}.{ext}")
        # no timestamps: the same data gives the same files
        meta = {"Software": None} if ext == "png" else {"Date": None}
        fig.savefig(path, dpi=150, metadata=meta)
        print(f"wrote {path}", file=sys.stderr)
    plt.close(fig)


def plain_log_ticks(axis, subs=(2.0, 5.0)):
    """A log axis labelled in plain numbers (1, 2, 5, 10, ...: the decades and
    subs times them) rather than powers of ten."""
    plain = ticker.FuncFormatter(lambda v, _pos: f"{v:g}")
    axis.set_major_formatter(plain)
    axis.set_minor_locator(ticker.LogLocator(base=10, subs=subs))
    axis.set_minor_formatter(plain)
