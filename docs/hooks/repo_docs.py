"""MkDocs hooks of the documentation site (``mkdocs.yml``: ``hooks``); not a page (``exclude_docs``).

1. **Sections of the repository's own Markdown files.** A page line

       <!-- include: README.md | Push mechanics | body, level=2 -->

   is replaced by the section of ``README.md`` (relative to the repository root) whose heading text
   starts with ``Push mechanics``, down to the next heading of the same or a higher level.
   ``(opening)`` takes the text between the file's title and its first ``##`` heading; no section
   name takes the whole file. Options: ``body`` leaves the heading line out, ``nosub`` ends the
   section at its first sub-heading, ``level=N`` moves the section's heading to level N (and its
   sub-headings with it), ``code=LANG`` shows the whole file as a code block (a script, a YAML
   file). Headings inside code fences do not count. So the site shows what the
   README says today rather than a copy that drifts; a section that is not there any more fails
   the build (strict mode) naming the page and the heading.

   Relative links in an included section point into the repository, not into the site: a link to a
   file under ``docs/`` is rewritten relative to the page, any other becomes its text followed by the
   path in code, and an image outside ``docs/`` becomes its caption and path.

2. **Module docstrings and schemas.** ``<!-- docstring: tooltransfer.planner.planning.plan -->`` is replaced by that
   module's docstring (read from its source, not imported; a reST ``::`` before a literal block
   becomes ``:``). ``<!-- schema: tooltransfer.problems.task.Task -->`` imports the pydantic model and writes a
   table of its fields, nested models as dotted paths (type, default, description). Pages outside
   the API reference use these rather than a second mkdocstrings rendering of an object, which
   would give one identifier two URLs.

3. **Sphinx roles in docstrings.** The code's docstrings cross-reference with Sphinx roles
   (``:func:`tooltransfer.planner.planning.solve.solve```), which Markdown renders as ``:func:<code>...</code>``. The
   role is dropped and the name becomes an optional mkdocs-autorefs reference: a link where the name is
   documented on the site, plain code where it is not (never a warning). ``~a.b.C`` shows ``C``.

4. **Only the package's own modules are walked.** The repository root is the package ``tooltransfer``,
   so griffe (mkdocstrings' loader), which walks every folder under a package for modules, also walked
   ``.venv`` (the whole virtual environment: 1.2 million paths, some 45 s of the build's 50 s).
   :func:`on_startup` makes it skip folders without an ``__init__.py`` (``.venv``, ``build``, ``tests``,
   ``benchmarks``; every subpackage of the project has one).
"""

from __future__ import annotations

import ast
import html
import importlib
import inspect
import json
import logging
import os
import re
import sys
from pathlib import Path
from typing import Any

log = logging.getLogger("mkdocs.hooks.repo_docs")

INCLUDE = re.compile(r"^<!--\s*include:\s*(?P<args>.*?)\s*-->\s*$", re.MULTILINE)
DOCSTRING = re.compile(r"^<!--\s*docstring:\s*(?P<module>[\w.]+)\s*-->\s*$", re.MULTILINE)
SCHEMA = re.compile(r"^<!--\s*schema:\s*(?P<model>[\w.]+)\s*-->\s*$", re.MULTILINE)
HEADING = re.compile(r"^(?P<hashes>#{1,6})\s+(?P<text>.*?)\s*#*\s*$")
FENCE = re.compile(r"^\s*(```|~~~)")
LINK = re.compile(r"(?P<bang>!?)\[(?P<text>[^\]]*)\]\((?P<target>[^)\s]+)(?P<title>\s+\"[^\"]*\")?\)")
ROLE = re.compile(r":(?:py:)?(?:func|mod|class|meth|data|attr|exc|obj|const|type):<code>(?P<name>[^<]*)</code>")


def _root(config: Any) -> Path:
    return Path(config["config_file_path"]).resolve().parent


def _headings(lines: list[str]) -> list[tuple[int, int, str]]:
    """(line index, level, text) of every Markdown heading outside code fences."""
    out, fenced = [], False
    for i, line in enumerate(lines):
        if FENCE.match(line):
            fenced = not fenced
            continue
        m = None if fenced else HEADING.match(line)
        if m:
            out.append((i, len(m["hashes"]), m["text"]))
    return out


def _section(text: str, name: str, nosub: bool = False) -> list[str] | None:
    lines = text.splitlines()
    heads = _headings(lines)
    if not name:
        return lines
    if name == "(opening)":
        first = next((i for i, level, _ in heads if level == 1), -1)
        end = next((i for i, level, _ in heads if level == 2 and i > first), len(lines))
        return lines[first + 1:end]
    for k, (i, level, title) in enumerate(heads):
        if title.startswith(name):
            end = next((j for j, lv, _ in heads[k + 1:] if nosub or lv <= level), len(lines))
            return lines[i:end]
    return None


def _relevel(lines: list[str], level: int) -> list[str]:
    heads = _headings(lines)
    if not heads:
        return lines
    shift = level - heads[0][1]
    out = list(lines)
    for i, lv, title in heads:
        out[i] = "#" * min(6, max(1, lv + shift)) + " " + title
    return out


def _links(text: str, source: Path, page: Path, docs: Path, root: Path) -> str:
    def fix(m: re.Match[str]) -> str:
        target = m["target"]
        if re.match(r"^[a-z][a-z0-9+.-]*:", target) or target.startswith("#"):
            return m[0]
        path, _, anchor = target.partition("#")
        resolved = (source.parent / path).resolve()
        if resolved.is_relative_to(docs):
            rel = Path(*([".."] * len(page.parent.parts))) / resolved.relative_to(docs)
            return f"{m['bang']}[{m['text']}]({rel.as_posix()}{'#' + anchor if anchor else ''}{m['title'] or ''})"
        shown = resolved.relative_to(root).as_posix() if resolved.is_relative_to(root) else path
        if m["bang"]:
            return f"*{m['text'] or 'figure'}* (`{shown}` in the repository)"
        return f"{m['text']} (`{shown}`)"

    return LINK.sub(fix, text)


def _module_docstring(root: Path, module: str) -> str | None:
    """The docstring of ``module`` (``tooltransfer.x.y``: the repository's root is the package)."""
    parts = module.split(".")
    base = root.joinpath(*(parts[1:] if parts[0] == "tooltransfer" else parts))
    path = base / "__init__.py" if base.is_dir() else base.with_suffix(".py")
    if not path.is_file():
        return None
    doc = ast.get_docstring(ast.parse(path.read_text(encoding="utf-8")))
    if doc is None:
        return None
    return re.sub(r"::$", ":", doc, flags=re.MULTILINE)


def _type(prop: dict[str, Any], defs: dict[str, Any]) -> str:
    if "const" in prop:
        return f"`{json.dumps(prop['const'])}`"
    if "enum" in prop:
        return " or ".join(f"`{json.dumps(v)}`" for v in prop["enum"])
    if "$ref" in prop:
        return f"`{prop['$ref'].rsplit('/', 1)[-1]}`"
    for key in ("anyOf", "oneOf"):
        if key in prop:
            parts = [_type(p, defs) for p in prop[key] if p.get("type") != "null"]
            optional = any(p.get("type") == "null" for p in prop[key])
            return " or ".join(parts) + (" or `null`" if optional else "")
    kind = prop.get("type", "")
    if kind == "array":
        if "prefixItems" in prop:
            items = [_type(p, defs) for p in prop["prefixItems"]]
            if len(set(items)) == 1 and items[0] in ("number", "integer", "2 numbers"):
                return f"{len(items)} {'points' if items[0] == '2 numbers' else items[0] + 's'}"
            return "(" + ", ".join(items) + ")"
        return f"list of {_type(prop.get('items', {}), defs)}"
    return kind or "any"


def _refs(prop: dict[str, Any]) -> list[str]:
    if "$ref" in prop:
        return [prop["$ref"].rsplit("/", 1)[-1]]
    out: list[str] = []
    for key in ("anyOf", "oneOf"):
        for p in prop.get(key, []):
            out += _refs(p)
    if "items" in prop:
        out += _refs(prop["items"])
    return out


def _schema_rows(schema: dict[str, Any], defs: dict[str, Any], prefix: str, seen: tuple[str, ...],
                 tag: str = "") -> list[str]:
    rows = []
    required = set(schema.get("required", []))
    for name, prop in schema.get("properties", {}).items():
        path = f"{prefix}{name}"
        refs = [r for r in _refs(prop) if "properties" in defs.get(r, {})]
        default = prop.get("default", "")
        shown = "" if isinstance(default, dict) or name in required else f"`{json.dumps(default)}`"
        desc = prop.get("description") or (defs[refs[0]].get("description", "") if len(refs) == 1 else "")
        if name in required:
            desc = ("**required**. " + desc).strip()
        desc = (tag + desc).replace("|", "\\|").replace("\n", " ")
        rows.append(f"| `{path}` | {_type(prop, defs)} | {shown} | {desc} |")
        many = "items" in prop or any("items" in p for p in prop.get("anyOf", []))
        for ref in refs:
            if ref in seen:
                continue
            sub_tag = f"`{ref}`: " if len(refs) > 1 else ""
            rows += _schema_rows(defs[ref], defs, f"{path}[]." if many else f"{path}.", (*seen, ref), sub_tag)
    return rows


def _schema_table(root: Path, target: str) -> str:
    module, _, name = target.rpartition(".")
    if str(root) not in sys.path:
        sys.path.insert(0, str(root))
    schema = getattr(importlib.import_module(module), name).model_json_schema()
    rows = _schema_rows(schema, schema.get("$defs", {}), "", ())
    return "\n".join(["| field | type | default | meaning |", "|---|---|---|---|", *rows]) + "\n"


def on_startup(command: str, dirty: bool) -> None:
    """Before the build: griffe's walk for submodules skips folders that are not regular packages (item 4
    of the module docstring). griffe has no public option for this; where its finder changes, the walk is
    left as it is (slower, same site)."""
    try:
        from griffe._internal.finder import ModuleFinder
    except ImportError:  # another griffe: leave its walk alone
        return
    walk = getattr(ModuleFinder, "_filter_py_modules", None)
    if walk is None or not hasattr(ModuleFinder, "extensions_set") or \
            list(inspect.signature(walk).parameters) != ["self", "path"]:
        return

    def packages_only(self: Any, path: Path) -> Any:
        """griffe's own walk (every file with a module's extension), into regular packages only."""
        for root, dirs, files in os.walk(path, topdown=True, followlinks=True):
            dirs[:] = [d for d in dirs if d != "__pycache__" and os.path.isfile(os.path.join(root, d, "__init__.py"))]
            yield from (Path(root, f) for f in files if os.path.splitext(f)[1] in self.extensions_set)

    ModuleFinder._filter_py_modules = packages_only  # type: ignore[method-assign]


def on_page_markdown(markdown: str, page: Any, config: Any, files: Any) -> str:
    root = _root(config)
    docs = Path(config["docs_dir"]).resolve()

    def include(m: re.Match[str]) -> str:
        args = [a.strip() for a in m["args"].split("|")]
        rel, name = args[0], args[1] if len(args) > 1 else ""
        options = [o.strip() for o in args[2].split(",")] if len(args) > 2 else []
        source = root / rel
        if not source.is_file():
            log.warning("%s: include: no file %s", page.file.src_path, rel)
            return ""
        lang = next((o.split("=", 1)[1] for o in options if o.startswith("code=")), None)
        if lang is not None:
            return f"```{lang}\n{source.read_text(encoding='utf-8').rstrip()}\n```\n"
        lines = _section(source.read_text(encoding="utf-8"), name, "nosub" in options)
        if lines is None:
            log.warning("%s: include: %s has no section whose heading starts with %r", page.file.src_path, rel, name)
            return ""
        for opt in options:
            if opt.startswith("level="):
                lines = _relevel(lines, int(opt.split("=", 1)[1]))
        if "body" in options and lines and _headings(lines[:1]):
            lines = lines[1:]
        return _links("\n".join(lines).strip("\n"), source, Path(page.file.src_path), docs, root) + "\n"

    def docstring(m: re.Match[str]) -> str:
        doc = _module_docstring(root, m["module"])
        if doc is None:
            log.warning("%s: docstring: no module docstring of %s", page.file.src_path, m["module"])
            return ""
        return doc + "\n"

    markdown = INCLUDE.sub(include, markdown)
    markdown = DOCSTRING.sub(docstring, markdown)
    return SCHEMA.sub(lambda m: _schema_table(root, m["model"]), markdown)


def on_page_content(content: str, page: Any, config: Any, files: Any) -> str:
    def ref(m: re.Match[str]) -> str:
        name = html.unescape(m["name"]).strip()
        ident = name.lstrip("~").removesuffix("()")
        shown = ident.rsplit(".", 1)[-1] if name.startswith("~") else name
        return f'<autoref identifier="{html.escape(ident)}" optional><code>{html.escape(shown)}</code></autoref>'

    return ROLE.sub(ref, content)
