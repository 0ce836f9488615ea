"""The report pages: one self-contained HTML file with relative links to its images.

A tiny inline script counts, once the page has loaded, the images that really loaded
(``complete && naturalWidth > 0``) and writes the counts into ``document.body.dataset``
(``imagesLoaded``, ``imagesTotal``), which the browser test reads from the DOM.
"""

from __future__ import annotations

from dataclasses import dataclass, field
from pathlib import Path

import jinja2

from ehlfoam._io import atomic_write_text


@dataclass
class Figure:
    """An image on the page: ``src`` relative to the page, a caption, an optional link."""

    src: str
    title: str
    caption: str = ""
    href: str | None = None


@dataclass
class Table:
    """A table: header cells and rows of cells (text; a cell may be (text, href))."""

    title: str
    header: list[str]
    rows: list[list]
    note: str = ""


@dataclass
class Page:
    """Everything a report page shows."""

    title: str
    status: str                          # ok | warn | fail (the banner's colour)
    status_text: str
    summary: list[str] = field(default_factory=list)
    figures: list[Figure] = field(default_factory=list)
    tables: list[Table] = field(default_factory=list)
    log_tail: list[str] = field(default_factory=list)
    log_href: str | None = None
    problems: list[str] = field(default_factory=list)
    links: list[tuple[str, str]] = field(default_factory=list)
    footer: str = ""
    thumbnails: Table | None = None      # batch index (cells may hold an image)
    lead_tables: list[Table] = field(default_factory=list)   # shown right after the banner


_TEMPLATE = """<!DOCTYPE html>
<html lang="en">
<head>
<meta charset="utf-8">
<meta name="viewport" content="width=device-width, initial-scale=1">
<title>{{ page.title }}</title>
<style>
 body { font-family: system-ui, -apple-system, "Segoe UI", Roboto, sans-serif; margin: 1.5em auto;
        max-width: 1100px; padding: 0 1em; color: #1d1d1f; line-height: 1.45; }
 h1 { font-size: 1.5em; margin-bottom: 0.2em; } h2 { font-size: 1.15em; margin-top: 1.6em;
        border-bottom: 1px solid #ddd; padding-bottom: 0.2em; }
 .banner { padding: 0.7em 1em; border-radius: 6px; font-weight: 600; margin: 0.8em 0; }
 .ok { background: #e3f4e6; border: 1px solid #7cc08a; }
 .warn { background: #fff4d6; border: 1px solid #e0b84a; }
 .fail { background: #fde2e0; border: 1px solid #d9534f; font-size: 1.1em; }
 .summary { margin: 0.3em 0; }
 figure { margin: 1.2em 0; } figure img { max-width: 100%; border: 1px solid #e4e4e4; }
 figcaption { font-size: 0.9em; color: #444; }
 table { border-collapse: collapse; font-size: 0.88em; margin: 0.5em 0; }
 th, td { border: 1px solid #ddd; padding: 0.25em 0.6em; text-align: left; vertical-align: top; }
 th { background: #f4f5f7; } td.num { text-align: right; font-variant-numeric: tabular-nums; }
 td img { max-width: 200px; }
 pre.log { background: #1e1e1e; color: #e6e6e6; padding: 0.8em; overflow-x: auto;
           font-size: 0.8em; border-radius: 4px; }
 .note { font-size: 0.85em; color: #555; } .problems { color: #8a3b00; }
 footer { margin-top: 2em; font-size: 0.8em; color: #777; }
</style>
</head>
<body>
<h1>{{ page.title }}</h1>
<div class="banner {{ page.status }}" id="status">{{ page.status_text }}</div>
{% for line in page.summary %}<p class="summary">{{ line }}</p>
{% endfor %}
{% for t in page.lead_tables %}{{ table(t) }}{% endfor %}
{% if page.log_tail %}
<h2 id="log">Last lines of the solver log{% if page.log_href %} (<a href="{{ page.log_href }}">full log</a>){% endif %}</h2>
<pre class="log">{{ page.log_tail | join("\n") }}</pre>
{% endif %}
{% if page.problems %}
<h2>What could not be shown</h2>
<ul class="problems">{% for p in page.problems %}<li>{{ p }}</li>{% endfor %}</ul>
{% endif %}
{% for f in page.figures %}
<h2>{{ f.title }}</h2>
<figure>{% if f.href %}<a href="{{ f.href }}">{% endif %}<img src="{{ f.src }}" alt="{{ f.title }}">{% if f.href %}</a>{% endif %}
{% if f.caption %}<figcaption>{{ f.caption }}</figcaption>{% endif %}</figure>
{% endfor %}
{% for t in page.tables %}{{ table(t) }}{% endfor %}
{% if page.thumbnails %}{{ table(page.thumbnails) }}{% endif %}
{% if page.links %}
<h2>Files</h2>
<ul>{% for text, href in page.links %}<li><a href="{{ href }}">{{ text }}</a></li>{% endfor %}</ul>
{% endif %}
<footer>{{ page.footer }}</footer>
<script>
window.addEventListener("load", function () {
  var imgs = Array.prototype.slice.call(document.images);
  var ok = imgs.filter(function (i) { return i.complete && i.naturalWidth > 0; });
  document.body.dataset.imagesTotal = String(imgs.length);
  document.body.dataset.imagesLoaded = String(ok.length);
});
</script>
</body>
</html>
"""

_TABLE = """{% macro table(t) %}
<h2>{{ t.title }}</h2>
{% if t.note %}<p class="note">{{ t.note }}</p>{% endif %}
<table>
<tr>{% for h in t.header %}<th>{{ h }}</th>{% endfor %}</tr>
{% for row in t.rows %}<tr>{% for c in row %}{{ cell(c) }}{% endfor %}</tr>
{% endfor %}</table>
{% endmacro %}
{% macro cell(c) %}{% if c is mapping %}<td{% if c.num %} class="num"{% endif %}>{% if c.href %}<a href="{{ c.href }}">{% endif %}{% if c.img %}<img src="{{ c.img }}" alt="{{ c.text }}" loading="eager">{% else %}{{ c.text }}{% endif %}{% if c.href %}</a>{% endif %}</td>{% else %}<td>{{ c }}</td>{% endif %}{% endmacro %}
"""


def cell(text, href: str | None = None, img: str | None = None, num: bool = False) -> dict:
    """A table cell with an optional link, image or right alignment."""
    return {"text": "" if text is None else str(text), "href": href, "img": img, "num": num}


def _environment() -> jinja2.Environment:
    env = jinja2.Environment(autoescape=True, trim_blocks=False, lstrip_blocks=False,
                             undefined=jinja2.StrictUndefined)
    return env


def render(page: Page) -> str:
    """The page as HTML text."""
    env = _environment()
    macros = env.from_string(_TABLE).module
    template = env.from_string(_TEMPLATE)
    return template.render(page=page, table=macros.table)


def write_page(page: Page, path: Path) -> Path:
    """Write ``page`` to ``path`` (atomically)."""
    path = Path(path)
    path.parent.mkdir(parents=True, exist_ok=True)
    atomic_write_text(path, render(page))
    path.chmod(0o644)          # readable by a web server, like the PNGs
    return path
