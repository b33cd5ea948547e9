"""Self-contained HTML pages with Bokeh plots: the batch report and the plan viewer.

One file that opens without a network: Bokeh's scripts and styles are inlined (``bokeh.resources.INLINE``,
only the bundles the page's models need), and so are the page's own style and script. The plots are
Bokeh models laid into the page by name (``{{ embed(roots.NAME) }}`` in the body); the body's own
HTML is escaped by its author (:func:`esc`). Bokeh is an optional dependency (the ``report``
extra): :func:`require_bokeh` says what to install.
"""

from __future__ import annotations

import html
import json
from collections.abc import Sequence
from pathlib import Path
from typing import Any

#: The pages' common style: readable tables, panels side by side where there is room.
BASE_CSS = """
body { font-family: system-ui, sans-serif; margin: 1.2em 2em; color: #222; }
h1 { font-size: 1.5em; } h2 { font-size: 1.2em; margin-top: 1.6em; }
table.data { border-collapse: collapse; font-size: 0.85em; }
table.data th, table.data td { border-bottom: 1px solid #ddd; padding: 2px 8px; text-align: right; }
table.data th { background: #f4f4f4; position: sticky; top: 0; cursor: default; }
table.data td.text, table.data th.text { text-align: left; }
table.data td.reason { text-align: left; white-space: pre-wrap; max-width: 70em; }
.row { display: flex; flex-wrap: wrap; gap: 1.5em; align-items: flex-start; }
.note { color: #555; font-size: 0.9em; max-width: 70em; }
.s-solved { color: #1a7f37; } .s-infeasible { color: #8250df; } .s-unknown, .s-violated { color: #bc4c00; }
.s-error, .s-timeout { color: #cf222e; }
"""


def require_bokeh() -> None:
    """Raise a ``ModuleNotFoundError`` (name ``bokeh``) saying how to install Bokeh when it is missing."""
    try:
        import bokeh  # noqa: F401
    except ImportError as exc:
        raise ModuleNotFoundError('the HTML pages need Bokeh: pip install "tooltransfer[report]" (or pip install '
                                  'bokeh)', name="bokeh") from exc


def esc(text: object) -> str:
    """``text`` escaped for HTML (quotes too)."""
    return html.escape(str(text), quote=True)


def script_json(data: Any) -> str:
    """``data`` as compact JSON safe inside a ``<script>`` element: every ``<`` written ``\\u003c``
    (the same string to a JSON reader)."""
    return json.dumps(data, separators=(",", ":"), allow_nan=False).replace("<", "\\u003c")


def json_script(element_id: str, data: Any) -> str:
    """``data`` as JSON in a ``<script type="application/json">`` element (every ``<`` written
    ``\\u003c``, so no value can close the element or open a comment in it)."""
    text = script_json(data)
    return f'<script type="application/json" id="{esc(element_id)}">{text}</script>'


def plot(name: str) -> str:
    """The marker that :func:`write_page` replaces by the Bokeh model named ``name``."""
    return f"<!--plot:{name}-->"


def write_page(path: str | Path, title: str, body: str, models: Sequence[Any], *, css: str = "",
               script: str = "") -> Path:
    """Write a page: ``body`` (HTML, with a :func:`plot` marker where each named Bokeh model of
    ``models`` goes), the base and ``css`` styles, Bokeh's inlined resources and ``script``
    (JavaScript run after Bokeh's own script, once the page is parsed: it may wait for the models
    with ``Bokeh.documents``). Written atomically; returns the path.

    The body's text is handed to the template as values, never parsed as a template (a reason holding
    ``{{`` stays text)."""
    import re

    from bokeh.embed import file_html
    from bokeh.resources import INLINE
    from jinja2 import Template

    from tooltransfer.atomic import write_text

    parts = re.split(r"<!--plot:([A-Za-z0-9_]+)-->", body)
    chunks = {f"chunk_{i}": text for i, text in enumerate(parts[0::2])}
    layout = "".join(f"{{{{ chunk_{i} }}}}" + (f"{{{{ embed(roots.{parts[2 * i + 1]}) }}}}"
                                               if 2 * i + 1 < len(parts) else "") for i in range(len(chunks)))
    template = Template(
        "{% from macros import embed %}<!DOCTYPE html>\n<html lang=\"en\">\n<head>\n<meta charset=\"utf-8\">\n"
        "<title>{{ title }}</title>\n{{ bokeh_css }}\n{{ bokeh_js }}\n<style>{{ page_css }}</style>\n</head>\n"
        "<body>\n" + layout + "\n{{ plot_script }}\n<script>{{ page_script }}</script>\n</body>\n</html>\n")
    text = file_html(list(models), INLINE, title, template=template,
                     template_variables={"page_css": BASE_CSS + css, "page_script": script, **chunks})
    return write_text(path, text)
