"""Plotly figures in a self-contained page with plotly.js embedded compressed (1.9 MB instead of 4.8 MB).

plotly.js is embedded gzip-compressed in base64; the page unpacks it with the browser's
DecompressionStream (Chrome 80, Firefox 113, Safari 16.4 and later), then draws the
figures, then runs the page's own script.  No network is needed.  A browser without
DecompressionStream shows a message in place of the figures.

    parts = [figure_div("view", figure), ..., plotly_loader(["view", ...], "/* after drawing */")]
"""

from __future__ import annotations

import base64
import gzip
import html
import json
from functools import lru_cache

import plotly.graph_objects as go
import plotly.io
from plotly.offline import get_plotlyjs

PACKED_ID = "plotly-gzip-base64"

LOADER = """
(async function () {
  var packed = document.getElementById("%(packed)s").textContent;
  var bytes = Uint8Array.from(atob(packed), function (c) { return c.charCodeAt(0); });
  var stream = new Blob([bytes]).stream().pipeThrough(new DecompressionStream("gzip"));
  var library = document.createElement("script");
  library.textContent = await new Response(stream).text();
  document.head.appendChild(library);
  var ids = %(ids)s;
  for (var n = 0; n < ids.length; n++) {
    var figure = JSON.parse(document.getElementById(ids[n] + "-figure").textContent);
    await Plotly.newPlot(ids[n], figure.data, figure.layout, {responsive: true});
    if (figure.frames) { await Plotly.addFrames(ids[n], figure.frames); }
  }
  %(after)s
})().catch(function (error) {
  var ids = %(ids)s;
  for (var n = 0; n < ids.length; n++) {
    document.getElementById(ids[n]).textContent = "The figures could not be drawn (" + error +
      "); this page needs a browser from 2023 or later.";
  }
  throw error;
});
"""


def figure_div(div_id: str, figure: go.Figure) -> str:
    """A placeholder for `figure` (drawn by the loader) and the figure's JSON beside it."""
    text = plotly.io.to_json(figure, validate=False).replace("</", "<\\/")  # JSON may not close the script
    height = figure.layout.height
    style = f' style="height:{height}px"' if height else ""
    return (f'<div id="{html.escape(div_id)}"{style}></div>\n'
            f'<script type="application/json" id="{html.escape(div_id)}-figure">{text}</script>')


def plotly_loader(div_ids: list[str], after: str = "") -> str:
    """The compressed plotly.js and the script that unpacks it, draws the figures of `div_ids` and runs `after` (JS)."""
    return (f'<script type="application/octet-stream" id="{PACKED_ID}">{packed_plotly()}</script>\n'
            f"<script>{LOADER % {'packed': PACKED_ID, 'ids': json.dumps(div_ids), 'after': after}}</script>")


@lru_cache(maxsize=1)
def packed_plotly() -> str:
    """plotly.js, gzip-compressed (no time stamp: the same bytes every run), in base64."""
    return base64.b64encode(gzip.compress(get_plotlyjs().encode("utf-8"), compresslevel=9, mtime=0)).decode("ascii")
