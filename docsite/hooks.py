"""MkDocs hooks of the documentation site (``mkdocs.yml``: ``hooks``).

The pages are plain Markdown that also reads well on a repository host, so they cite and
point the way the code does; this hook turns both into links on the site:

- a citation key such as ``[Thesis2019]`` becomes a link to its entry of the bibliography
  (``bibliography.md#thesis2019``); a key the bibliography does not define is a warning,
  which fails the strict build;
- a mention of another page, ``docs/verify.md`` (in backticks or not, with an optional
  ``#anchor``), becomes a link to that page titled with the page's heading; MkDocs checks
  the link, so a page that does not exist fails the strict build too.

Fenced code blocks are left alone, and so are code spans other than a page mention.
"""
from __future__ import annotations

import logging
import re
from pathlib import Path

log = logging.getLogger("mkdocs.plugins.pixelkit")

#: a bracketed word that may be a citation key: linked when the bibliography defines it
#: (``[EMVA1288]``, ``[GF180MCU]``, ``[ngspice]``); Markdown links and their definitions excluded
CITE = re.compile(r"(?<![\w`\[])\[([A-Za-z][A-Za-z0-9.-]*[A-Za-z0-9])\](?![(:\[\]])")
#: an author-year key (as ``tests/test_repository_pointers.py`` reads it): one the bibliography
#: does not define is a warning (an error in the strict build); other bracketed words are prose
AUTHOR_YEAR = re.compile(r"[A-Z][A-Za-z]*(?:19|20)\d\d[a-z]?")
PAGE = r"docs/([A-Za-z0-9_-]+\.md)(#[A-Za-z0-9_-]+)?"
PAGE_SPAN = re.compile(r"`" + PAGE + r"`")
#: a bare mention: also in parentheses, "(docs/verify.md)", but not a Markdown link's target "](docs/..."
PAGE_BARE = re.compile(r"(?<![\w/\[`.-])(?<!\]\()" + PAGE + r"(?![\w/])")
FENCE = re.compile(r"^\s*(```|~~~)")
SPANS = re.compile(r"(`+)(.+?)\1")
BIB_HEADING = re.compile(r"^#+\s*\[([A-Za-z][A-Za-z0-9.-]*[A-Za-z0-9])\]\s*$", re.M)


def bibliography_keys(docs_dir) -> set[str]:
    """The keys the bibliography defines (its ``### [Key]`` headings)."""
    return set(BIB_HEADING.findall((Path(docs_dir) / "bibliography.md").read_text(encoding="utf-8")))


def page_titles(docs_dir) -> dict[str, str]:
    """{file name: its first ``# `` heading, without code marks} of the pages in ``docs_dir``."""
    titles = {}
    for p in Path(docs_dir).glob("*.md"):
        m = re.search(r"^# (.+)$", p.read_text(encoding="utf-8"), re.M)
        titles[p.name] = m.group(1).replace("`", "").strip() if m else p.stem
    return titles


def page_link(m, root: str, titles: dict) -> str:
    """The link for a page mention ``m`` (groups: file name, anchor)."""
    return f"[{titles.get(m.group(1), m.group(1))}]({root}{m.group(1)}{m.group(2) or ''})"


def link_text(text: str, keys: set[str], root: str, where: str, titles: dict) -> str:
    """One stretch of prose (no code): citations and page mentions as links."""
    def cite(m):
        if m.group(1) not in keys:
            if AUTHOR_YEAR.fullmatch(m.group(1)):
                log.warning("%s: citation key [%s] is not in the bibliography", where, m.group(1))
            return m.group(0)
        return f"[[{m.group(1)}]]({root}bibliography.md#{m.group(1).lower()})"
    text = PAGE_BARE.sub(lambda m: page_link(m, root, titles), text)
    return CITE.sub(cite, text)


def link_line(line: str, keys: set[str], root: str, where: str, titles: dict) -> str:
    """A Markdown line outside fenced blocks: code spans kept, except page mentions."""
    out, last = [], 0
    for m in SPANS.finditer(line):
        out.append(link_text(line[last:m.start()], keys, root, where, titles))
        span = m.group(0)
        page = PAGE_SPAN.fullmatch(span)
        out.append(page_link(page, root, titles) if page else span)
        last = m.end()
    out.append(link_text(line[last:], keys, root, where, titles))
    return "".join(out)


def link_markdown(markdown: str, keys: set[str], where: str = "page", root: str = "",
                  is_bibliography: bool = False, titles: dict | None = None) -> str:
    """The page's Markdown with citations and page mentions linked, fenced blocks untouched;
    ``root`` is the way from the page's folder up to ``docs/`` (``""``, ``"../"``...)."""
    lines, fenced = [], None
    for line in markdown.split("\n"):
        f = FENCE.match(line)
        if fenced:
            fenced = None if f and f.group(1) == fenced else fenced
            lines.append(line)
        elif f:
            fenced = f.group(1)
            lines.append(line)
        elif is_bibliography and BIB_HEADING.match(line):
            lines.append(line)
        else:
            lines.append(link_line(line, keys, root, where, titles or {}))
    return "\n".join(lines)


#: a quoted kit figure's marker (``docsite/figures.py``): the test reads it, the site does not show it
FIGURE_MARK = re.compile(r"<!--fig [^>]*-->")
#: a ``dated:COMMIT`` mark: a figure of a past run, not checked against the kit as it is now; the site
#: shows its age beside it, so a reader never takes it for a figure the suite holds to the current kit
DATED_MARK = re.compile(r"<!--fig dated:([0-9a-f]{7,40})-->")


def show_dated(markdown: str) -> str:
    """Each ``dated:COMMIT`` mark as a visible superscript naming the commit (its title says what it
    means); every other mark removed."""
    markdown = DATED_MARK.sub(lambda m: f'<sup class="dated" title="measured at {m[1][:7]}; not re-checked '
                              f'against the kit as it is now">{m[1][:7]}</sup>', markdown)
    return FIGURE_MARK.sub("", markdown)


def on_page_markdown(markdown, page, config, files):
    src = page.file.src_uri
    docs = config["docs_dir"]
    markdown = show_dated(markdown)
    return link_markdown(markdown, bibliography_keys(docs), src, "../" * src.count("/"),
                         is_bibliography=src == "bibliography.md", titles=page_titles(docs))


#: an HTML tag, or a run of text between tags
_HTML = re.compile(r"(<[^>]*>)")
_KEEP = {"code", "pre", "a", "h1", "h2", "h3", "h4", "h5", "h6"}


def link_html(html: str, keys: set[str], bib_url: str, page_url=lambda name: None) -> str:
    """Citation keys and page mentions in generated HTML (the CLI reference from the commands' help,
    the API reference from the docstrings: text the Markdown hook never sees) as links: a key to
    ``bib_url#key``, ``docs/x.md`` to ``page_url("x.md")`` (None: left as it is); text inside code,
    links and headings kept as it is."""
    def page(m):
        url = page_url(m.group(1))
        return f'<a href="{url}{m.group(2) or ""}">{m.group(0)}</a>' if url else m.group(0)

    out, inside = [], []
    for part in _HTML.split(html):
        tag = re.match(r"<(/?)([A-Za-z0-9]+)", part) if part.startswith("<") else None
        if tag:
            name = tag.group(2).lower()
            if name in _KEEP and not part.endswith("/>"):
                if tag.group(1):
                    inside = inside[:-1] if inside and inside[-1] == name else inside
                else:
                    inside.append(name)
            out.append(part)
        elif inside or not part:
            out.append(part)
        else:
            part = PAGE_BARE.sub(page, part)
            out.append(CITE.sub(lambda m: f'<a href="{bib_url}#{m.group(1).lower()}">[{m.group(1)}]</a>'
                                if m.group(1) in keys else m.group(0), part))
    return "".join(out)


def on_page_content(html, page, config, files):
    if page.file.src_uri == "bibliography.md":
        return html
    from mkdocs.utils import get_relative_url
    bib = next((f for f in files if f.src_uri == "bibliography.md"), None)
    if bib is None:
        return html
    urls = {f.src_uri: get_relative_url(f.url, page.url) for f in files if f.src_uri.endswith(".md")}
    return link_html(html, bibliography_keys(config["docs_dir"]), get_relative_url(bib.url, page.url), urls.get)
