"""The one-page report of ``seatrack demo``: the situations, their comparisons and plots.

:func:`demo_text` is the plain-text comparison (printed and written to ``results.txt``),
:func:`demo_page` the HTML page: one section per situation with its table (method, what was
given, position RMSE, ratio to the best fixed-q EKF in hindsight), one sentence per method
on when to use it, and its figure inlined as a ``data:image/png;base64`` URI -- one
self-contained file, no server, no network. :func:`write_demo_page` writes it atomically.

For headless-browser tests the page sets ``data-sections`` on ``<body>`` (and, once loaded,
``data-images``: the figures the browser decoded), and each ``<section>`` carries
``data-key`` and ``data-rows``; figures are ``<img data-figure>``.
"""

from __future__ import annotations

import base64
import html
import math
from collections.abc import Sequence
from pathlib import Path

from seatrack.io.atomic import atomic_write
from seatrack.report.demo import WHEN
from seatrack.report.demo import Row
from seatrack.report.demo import Section

__all__ = ["demo_text", "demo_page", "write_demo_page"]

_CSS = """
body { font-family: system-ui, sans-serif; max-width: 1180px; margin: 1.5em auto;
       padding: 0 1em; color: #1d2733; line-height: 1.45; }
h1 { font-size: 1.6em; margin-bottom: 0.2em; }
h2 { font-size: 1.25em; border-bottom: 1px solid #d0d7de; padding-bottom: 0.2em;
     margin-top: 1.8em; }
table { border-collapse: collapse; margin: 0.6em 0; font-size: 0.92em; }
th, td { border: 1px solid #d0d7de; padding: 0.25em 0.6em; text-align: left; }
td.num { text-align: right; font-variant-numeric: tabular-nums; }
tr.best td { background: #eef7ee; }
tr.anchor td { color: #57606a; font-style: italic; }
img { max-width: 100%; border: 1px solid #d0d7de; }
pre { background: #f6f8fa; padding: 0.6em; overflow-x: auto; font-size: 0.88em; }
p.note { color: #57606a; font-size: 0.9em; }
"""


#: sets ``data-images`` on <body>: the figures the browser decoded (for headless tests)
_SCRIPT = (
    "window.addEventListener('load', function () {"
    " var n = 0; document.querySelectorAll('img').forEach(function (i) {"
    " if (i.complete && i.naturalWidth > 0) { n += 1; } });"
    " document.body.setAttribute('data-images', String(n)); });"
)


def _ratio(r: Row) -> str:
    return "" if math.isnan(r.ratio) else f"{r.ratio:.2f}"


def _first_uses(sections: Sequence[Section]) -> list[list[str]]:
    """Per section, the methods whose "when to use" sentence it shows (each method once, in
    the first section that runs it)."""
    seen: set[str] = set()
    out = []
    for s in sections:
        new = [m for m in s.methods if m in WHEN and m not in seen]
        seen.update(new)
        out.append(new)
    return out


def demo_text(sections: Sequence[Section], seconds: float) -> str:
    """The comparison as plain text: per section its rows, lines and, for each method the
    first time it appears, when to use it."""
    out = []
    for s, uses in zip(sections, _first_uses(sections), strict=True):
        out += [f"== {s.title} ({s.seconds:.1f} s) ==", s.situation]
        if s.rows:
            out.append(f"  {'method':<22}{'given':<42}{'pos RMSE m':>11}{'/best q':>9}")
            for r in s.rows:
                out.append(f"  {r.method:<22}{r.config:<42}{r.value:11.1f}{_ratio(r):>9}")
        out += [f"  {line}" for line in s.lines]
        out += [f"  use {m}: {WHEN[m]}" for m in uses]
        out.append("")
    out.append(f"demo total {seconds:.0f} s")
    return "\n".join(out) + "\n"


def _table(rows: Sequence[Row]) -> str:
    if not rows or all(math.isnan(r.ratio) for r in rows):
        return ""
    best = min(r.value for r in rows[:-1]) if len(rows) > 1 else math.nan
    body = []
    for i, r in enumerate(rows):
        cls = "anchor" if i == len(rows) - 1 else ("best" if r.value == best else "")
        body.append(
            f'<tr class="{cls}"><td>{html.escape(r.method)}</td><td>{html.escape(r.config)}</td>'
            f'<td class="num">{r.value:.1f}</td><td class="num">{_ratio(r)}</td></tr>'
        )
    head = "<tr><th>method</th><th>given (besides the sensor noise)</th>"
    head += "<th>position RMSE (m)</th><th>/ best fixed q</th></tr>"
    return f"<table>{head}{''.join(body)}</table>"


def _figure(path: Path | None, key: str) -> str:
    from seatrack.io.atomic import pending_output

    if path is None or not pending_output(path).is_file():
        return ""
    data = base64.b64encode(pending_output(path).read_bytes()).decode("ascii")
    return f'<img data-figure="{key}" alt="{key}" src="data:image/png;base64,{data}">'


def _section(s: Section, uses: Sequence[str]) -> str:
    when = "".join(f"<li><b>{html.escape(m)}</b>: {html.escape(WHEN[m])}</li>" for m in uses)
    lines = f"<pre>{html.escape(chr(10).join(s.lines))}</pre>" if s.lines else ""
    return (
        f'<section data-key="{s.key}" data-rows="{len(s.rows)}"><h2>{html.escape(s.title)}</h2>'
        f"<p>{html.escape(s.situation)}</p>{_table(s.rows)}{lines}<ul>{when}</ul>"
        f"{_figure(s.figure, s.key)}</section>"
    )


def demo_page(sections: Sequence[Section], seconds: float, runs: int) -> str:
    """The self-contained HTML page of the demo."""
    intro = (
        "Each method of seatrack in the situation it is made for. The tracking methods run "
        "as you would run them: their defaults plus the sensor's nominal noise (one row also "
        f"names the target class), on {runs} simulated runs drawn with seeds no method was "
        "tuned on. Each table ends with the constant-velocity EKF whose fixed process noise "
        "is the best on these very runs: an oracle no filter can choose in advance; a ratio "
        "below 1 beats it. Methods named <code>-spec</code> are the sources as written."
    )
    body = "".join(_section(s, u) for s, u in zip(sections, _first_uses(sections), strict=True))
    return (
        '<!DOCTYPE html><html lang="en"><head><meta charset="utf-8">'
        '<meta name="viewport" content="width=device-width, initial-scale=1">'
        f"<title>seatrack demo</title><style>{_CSS}</style><script>{_SCRIPT}</script></head>"
        f'<body data-sections="{len(sections)}"><h1>seatrack demo</h1><p>{intro}</p>'
        f'{body}<p class="note">Generated by <code>seatrack demo</code> in {seconds:.0f} s.'
        "</p></body></html>\n"
    )


def write_demo_page(
    path: str | Path, sections: Sequence[Section], seconds: float, runs: int
) -> Path:
    """Write :func:`demo_page` to ``path`` atomically."""
    with atomic_write(path) as fh:
        fh.write(demo_page(sections, seconds, runs))
    return Path(path)
