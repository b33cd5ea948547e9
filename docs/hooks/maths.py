"""MkDocs hook: the site's mathematics as MathML, converted while the site is built.

``pymdownx.arithmatex`` (``generic: true``, ``mkdocs.yml``) marks ``$...$`` and ``$$...$$`` in the
pages and in the docstrings mkdocstrings renders as ``<span class="arithmatex">\\(...\\)</span>`` and
``<div class="arithmatex">\\[...\\]</div>``; this hook replaces each by the MathML of its LaTeX
(``latex2mathml``, pure Python), which every current browser draws itself: no script, no font and
no network when a page is read. A formula the converter refuses is a warning naming the page and
the formula (an error under ``mkdocs build --strict``).
"""

from __future__ import annotations

import html
import logging
import re
from typing import Any

log = logging.getLogger("mkdocs.hooks.maths")

INLINE = re.compile(r'<span class="arithmatex">\\\((?P<tex>.*?)\\\)</span>', re.DOTALL)
BLOCK = re.compile(r'<div class="arithmatex">\\\[(?P<tex>.*?)\\\]</div>', re.DOTALL)


def _mathml(tex: str, display: str, page: Any) -> str:
    from latex2mathml.converter import convert

    source = html.unescape(tex).strip()
    try:
        return str(convert(source, display=display))
    except Exception as exc:  # the converter's own errors have no common base
        log.warning("%s: the formula %r does not convert to MathML (%s: %s)", page.file.src_path, source,
                    type(exc).__name__, exc)
        return f"<code>{html.escape(source)}</code>"


def on_page_content(content: str, page: Any, config: Any, files: Any) -> str:
    content = BLOCK.sub(lambda m: f'<div class="maths">{_mathml(m["tex"], "block", page)}</div>', content)
    return INLINE.sub(lambda m: _mathml(m["tex"], "inline", page), content)
