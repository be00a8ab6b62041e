"""``--figures png,svg,pdf``: the formats a command writes its reports' figures in (the commands that write
reports: run, sweep, evaluate, report).  PNG alone by default; the vector copies on request."""

from __future__ import annotations

import argparse

from rpbench.spec import DEFAULT_FIGURE_FORMATS, FIGURE_FORMATS, figure_formats


def add_figures_arg(parser: argparse.ArgumentParser, *, later: bool = True) -> None:
    """``--figures``; ``later``: say that ``rpbench report`` adds the vector copies to a written folder."""
    add = " (rpbench report DIR --figures svg,pdf adds them to a folder later)" if later else ""
    parser.add_argument(
        "--figures",
        default=",".join(DEFAULT_FIGURE_FORMATS),
        metavar="FORMATS",
        help=f"comma-separated figure formats of {', '.join(FIGURE_FORMATS)}: PNG is always written (the reports "
        f"show it), SVG and PDF copies for papers only when named (default {','.join(DEFAULT_FIGURE_FORMATS)})" + add,
    )


def formats_of(args: argparse.Namespace) -> tuple[str, ...]:
    """``--figures`` checked: the formats, PNG first; an unknown format is one error line (exit 2)."""
    given = getattr(args, "figures", None)  # a command without --figures (snapshot): the default
    return DEFAULT_FIGURE_FORMATS if given is None else figure_formats(given)
