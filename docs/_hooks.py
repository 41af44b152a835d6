"""mkdocs hook: pages built from files outside `docs/`, and the navigation that lists them.

- `benchmarks/index.md` and one page per `benchmarks/results/*.md` (with the figures they
  show), so that the site shows the measured results as they were written, with the command,
  commit and date at their top;
- `changelog.md` from the repository's `CHANGELOG.md`;
- the "API reference" and "Benchmarks" sections of the navigation list every page of
  `docs/api/` (in the order of `docs/api/index.md`) and every results page.

A docstring may refer to a private helper of its own module (`[`name`][]`, diffrax's style);
the site documents the public names only, so such a reference is shown as code, not reported
as a broken link. A broken reference to a public `fwid.` name still fails the strict build.

Nothing is fetched: the hook reads files of the checkout only.
"""

from __future__ import annotations

import logging
import re
from pathlib import Path

from mkdocs.structure.files import File

ROOT = Path(__file__).resolve().parents[1]
RESULTS = ROOT / "benchmarks" / "results"
API = ROOT / "docs" / "api"


def _title(text: str, fallback: str) -> str:
    for line in text.splitlines():
        if line.startswith("# "):
            return line[2:].strip().strip("`")
    return fallback


def _links_to_plain(text: str) -> str:
    """Relative links in a results file that point into the repository, not the site: keep
    their text, drop the link (a figure beside the file is kept: it is copied along)."""
    text = re.sub(r"(?<!!)\[([^\]]+)\]\((?!https?:|#)[^)]+\)", r"\1", text)
    return re.sub(r"!\[[^\]]*\]\(([^)/]+\.png)\)",
                  lambda m: m.group(0) if (RESULTS / m.group(1)).exists()
                  else f"*(figure `{m.group(1)}` not kept in the repository)*", text)


def results_pages() -> dict[str, str]:
    """The benchmarks pages: an index and one page per results Markdown file."""
    pages = {}
    rows = []
    for md in sorted(RESULTS.glob("*.md")):
        text = md.read_text()
        pages[f"benchmarks/{md.stem}.md"] = _links_to_plain(text)
        rows.append(f"| [{_title(text, md.stem)}]({md.stem}.md) | `benchmarks/results/{md.name}` |")
    index = ["# Benchmarks", "",
             "Each benchmark is one script in `benchmarks/` that answers one question and writes "
             "its figures to `benchmarks/results/NAME.md` (and `.json`), starting with the "
             "command, the commit and the date that produced them. The pages below are those "
             "files as they were written; the guide pages quote their figures.", "",
             "| results | file |", "|---|---|", *rows, ""]
    readme = ROOT / "benchmarks" / "README.md"
    if readme.exists():
        body = readme.read_text().split("\n", 1)[1]
        body = re.sub(r"^(#+) ", r"#\1 ", body, flags=re.M)  # below this page's title
        index += ["## The scripts", "", _links_to_plain(body)]
    pages["benchmarks/index.md"] = "\n".join(index)
    return pages


def _api_pages() -> list[str]:
    """The API pages in the order the index lists them."""
    index = API / "index.md"
    names = re.findall(r"\]\(([a-z_]+\.md)\)", index.read_text()) if index.exists() else []
    return list(dict.fromkeys(n for n in names if (API / n).exists()))


def _expand(nav: list, entry: str, section: list) -> list:
    out = []
    for item in nav:
        if isinstance(item, dict):
            (key, value), = item.items()
            if value == entry:
                item = {key: section}
            elif isinstance(value, list):
                item = {key: _expand(value, entry, section)}
        out.append(item)
    return out


def _nb_title(path: Path) -> str:
    """A notebook's first Markdown heading, else its file name."""
    import json

    try:
        for cell in json.loads(path.read_text()).get("cells", []):
            if cell.get("cell_type") == "markdown":
                for line in "".join(cell.get("source", "")).splitlines():
                    if line.startswith("# "):
                        return line[2:].strip()
    except (OSError, ValueError):
        pass
    return path.stem


def _listed(nav) -> set[str]:
    out = set()
    for item in nav:
        value = next(iter(item.values())) if isinstance(item, dict) else item
        if isinstance(value, list):
            out |= _listed(value)
        else:
            out.add(value)
    return out


def _append_unlisted(nav: list, section: str, entries: list[dict]) -> list:
    """Pages of a folder that the navigation does not list yet go at the end of `section`
    (a guide page or a notebook added without touching `mkdocs.yml` still shows)."""
    listed = _listed(nav)
    extra = [e for e in entries if next(iter(e.values())) not in listed]
    out = []
    for item in nav:
        if isinstance(item, dict) and section in item and isinstance(item[section], list):
            item = {section: [*item[section], *extra]}
        out.append(item)
    return out


def on_config(config):
    docs = Path(config["docs_dir"])
    guide = [{_title(p.read_text(), p.stem): f"guide/{p.name}"}
             for p in sorted((docs / "guide").glob("*.md"))]
    notebooks = [{_nb_title(p): f"notebooks/{p.name}"}
                 for p in sorted((docs / "notebooks").glob("*.ipynb"))]
    config["nav"] = _append_unlisted(_append_unlisted(config["nav"], "Guide", guide),
                                     "Notebooks", notebooks)
    api = [{"Overview": "api/index.md"}]
    for name in _api_pages():
        text = (API / name).read_text()
        api.append({_title(text, name[:-3]): f"api/{name}"})
    bench = [{"Overview": "benchmarks/index.md"}]
    for md in sorted(RESULTS.glob("*.md")):
        bench.append({md.stem: f"benchmarks/{md.stem}.md"})
    config["nav"] = _expand(_expand(config["nav"], "api/index.md", api),
                            "benchmarks/index.md", bench)
    logging.getLogger("mkdocs.plugins.mkdocs_autorefs._internal.plugin").addFilter(_private_refs)
    return config


def _private_refs(record: logging.LogRecord) -> bool:
    """Keep every autorefs message except an unresolved reference to a private helper."""
    found = re.search(r"Could not find cross-reference target '([^']+)'", record.getMessage())
    return not (found and not found.group(1).startswith("fwid."))


def on_files(files, config):
    generated = dict(results_pages())
    changelog = ROOT / "CHANGELOG.md"
    if changelog.exists():
        generated["changelog.md"] = changelog.read_text()
    for uri, content in generated.items():
        existing = files.get_file_from_path(uri)
        if existing is not None:
            files.remove(existing)
        files.append(File.generated(config, uri, content=content))
    for png in sorted(RESULTS.glob("*.png")):
        files.append(File.generated(config, f"benchmarks/{png.name}", abs_src_path=str(png)))
    return files


def on_page_content(html, page, config, files):
    """An unresolved reference to a private helper reads as its code, without brackets."""
    return re.sub(r"\[(<code>[^<]*</code>)\]\[\]", r"\1", html)
