"""The report as one HTML page, ``outputs/report/index.html``, beside ``index.md``: the same
tables and figures, plus the interactive 3-D workspace views (``pipeline.analyses.views``). It opens
offline from disk: Plotly's script is copied next to it and every view's data is inline (a page
opened from a file may not fetch other files). A view is drawn when its button is pressed, and
at most ``LIVE_VIEWS`` at a time stay drawn (browsers cap the WebGL contexts of a page).
"""

from __future__ import annotations

import html
import json
from dataclasses import dataclass
from pathlib import Path

from pipeline.app.results import write_text
from pipeline.errors import require

PLOTLY_JS = "plotly.min.js"
LIVE_VIEWS = 4

STYLE = """
body { font: 15px/1.5 system-ui, sans-serif; max-width: 1100px; margin: 2em auto; padding: 0 1em; color: #222; }
table { border-collapse: collapse; margin: 0.5em 0 1em; }
th, td { border: 1px solid #bbb; padding: 0.2em 0.6em; text-align: right; }
th:first-child, td:first-child { text-align: left; }
img { max-width: 100%; }
code { background: #f3f3f3; padding: 0 0.2em; }
figure.view { margin: 0 0 2em; }
figure.view button { font: inherit; padding: 0.3em 0.8em; cursor: pointer; }
figure.view .plot { width: 100%; }
"""

SCRIPT = """
const live = [];
function draw(figure) {
  const plot = figure.querySelector('.plot');
  const spec = JSON.parse(figure.querySelector('script[type="application/json"]').textContent);
  figure.querySelector('button').hidden = true;
  live.push(figure);
  if (live.length > %(live)d) {
    const old = live.shift();
    Plotly.purge(old.querySelector('.plot'));
    old.querySelector('button').hidden = false;
  }
  return Plotly.newPlot(plot, spec.data, spec.layout, {responsive: true});
}
document.querySelectorAll('figure.view button').forEach(
  button => button.addEventListener('click', () => draw(button.closest('figure.view'))));
""" % {"live": LIVE_VIEWS}


@dataclass(frozen=True)
class View:
    """An interactive view to embed: the Plotly JSON written by :func:`pipeline.analyses.views.write_view`."""
    path: Path
    caption: str


def write_page(blocks: list, out: Path, title: str) -> Path:
    """Render ``blocks`` (Markdown lines or :class:`View`) into ``out/index.html`` and copy
    Plotly's script beside it; returns the page."""
    MarkdownIt = require("markdown_it", "report", "the report's page").MarkdownIt
    get_plotlyjs = require("plotly.offline", "report", "the report's page").get_plotlyjs

    markdown = MarkdownIt("commonmark", {"html": False}).enable("table")
    body, views = [], 0
    text: list[str] = []
    for block in [*blocks, None]:
        if isinstance(block, str):
            text.append(block)
            continue
        body.append(markdown.render("\n".join(text)))
        text = []
        if block is not None:
            views += 1
            body.append(_view(block, views))
    if views:
        write_text(out / PLOTLY_JS, get_plotlyjs())
    page = (f'<!doctype html>\n<html lang="en">\n<head>\n<meta charset="utf-8">\n'
            f"<title>{html.escape(title)}</title>\n<style>{STYLE}</style>\n"
            + (f'<script src="{PLOTLY_JS}"></script>\n' if views else "")
            + "</head>\n<body>\n" + "\n".join(body)
            + (f"<script>{SCRIPT}</script>\n" if views else "") + "</body>\n</html>\n")
    write_text(out / "index.html", page)
    return out / "index.html"


def _view(view: View, number: int) -> str:
    spec = json.loads(view.path.read_text())
    data = json.dumps({"data": spec["data"], "layout": spec["layout"]}, separators=(",", ":"))
    data = data.replace("</", "<\\/")  # no "</script>" inside the inline data
    return (f'<figure class="view" id="view-{number}"><button type="button">Show the interactive '
            f"3-D view</button> {html.escape(view.caption)}\n"
            f'<div class="plot"></div>\n'
            f'<script type="application/json">{data}</script></figure>\n')
