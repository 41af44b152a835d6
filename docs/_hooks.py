"""mkdocs hook: pages built from files outside `docs/`, and the navigation that lists them.

- `benchmarks/index.md` (a table per benchmark, `BENCHMARKS`, naming what each results file
  holds) and one page per `benchmarks/results/*.md` (with the figures they show), so that the
  site shows the measured results as they were written, with the command, commit and date at
  their top;
- `changelog.md` from the repository's `CHANGELOG.md`;
- the "API reference" section of the navigation lists every page of `docs/api/` (in the order
  of `docs/api/index.md`); the "Benchmarks" section the overview and each benchmark's main
  results page by the benchmark's name (the other results files are linked from the overview).

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


#: The benchmarks, in the order the site lists them: a readable name, the question it answers,
#: and what each of its results files holds (by file stem; the first is its main page, shown in
#: the navigation). A results file not listed here goes under "Other results", by its title.
BENCHMARKS = (
    ("Speed of a fit",
     "How fast one fit and a batch of fits run, against scipy and a hand-written JAX loop.",
     {
        "speed": "one fit and batches of fits: fwid, the scipy baseline, a hand-written JAX loop",
        "speed_process": "the whole `fwid identify` process on 1, 16 and 64 flights, cold and warm",
        "simd":
            "a Gauss-Newton step's kernel for 64 flights in three layouts, against the machine",
        "distributed": "`fwid.fit_each` over one and two processes (`jax.distributed`)",
    }),
    ("Joint fits",
     "Whether one fit to several flights predicts held-out flights better than one flight's fit.",
     {
        "joint": "held-out error of joint against individual fits",
    }),
    ("Reconstruction", "How well raw tracking takes and autopilot logs become flight data.", {
        "reconstruction":
            "simulated Motive takes against the truth: states, loads, clock offset, time",
        "realdata":
            "real Flapper Drone flights: reconstructed specific force against the accelerometer",
    }),
    ("Test inputs",
     "How much a designed input gains over a 3211 of the same amplitude and length.",
     {
        "design": "designed inputs against classic ones: predicted and actual parameter errors",
        "design_ceiling": "the predicted gain under harder searches",
        "design_discrimination": "inputs that tell two diagnosed effects apart",
    }),
    ("Diagnosis: power",
     "How often `fwid diagnose` names the right effect, on a randomised benchmark split into a "
     "development and a held-out half.",
     {
        "diagnosis_power_heldout":
            "the held-out half, the latest fresh draw of its seeds (the seeds are in its "
            "command): coverage, decisiveness, false alarms, pairs, the SINDy peer beside fwid",
        "diagnosis_power_dev": "the development half, on which the settings were chosen",
        "diagnosis": "the first withheld-effect benchmark: gap closure per effect",
    }),
    ("Diagnosis: peers", "`fwid diagnose` beside a SINDy peer on the same flights.", {
        "diagnosis_peers_heldout": "fwid and SINDy on 12 held-out cases",
    }),
    ("Diagnosis: raw recordings",
     "The diagnosis end to end from raw tracking takes through `fwid reconstruct`.",
     {
        "raw_diagnosis_heldout": "held-out seeds: clean and lagging-actuator sets",
        "raw_diagnosis_dev": "development seeds",
    }),
    ("Diagnosis: time", "What `fwid diagnose` costs against `fwid identify` on the same flights.", {
        "diagnosis_speed": "clean flights, whole process",
        "diagnosis_speed_nonlinear": "flights with a `nonlinear-aero` verdict",
    }),
)


def _benchmarks() -> list[tuple[str, str, list[tuple[str, str]]]]:
    """The benchmarks with their results files that exist: (name, question, [(stem, what)])."""
    present = {md.stem: md for md in RESULTS.glob("*.md")}
    out, seen = [], set()
    for name, question, files in BENCHMARKS:
        rows = [(stem, what) for stem, what in files.items() if stem in present]
        seen |= set(files)
        if rows:
            out.append((name, question, rows))
    other = [(stem, _title(present[stem].read_text(), stem)) for stem in sorted(present)
             if stem not in seen]
    if other:
        out.append(("Other results", "Results files not yet described here.", other))
    return out


def results_pages() -> dict[str, str]:
    """The benchmarks pages: an index (a table per benchmark naming what each results file
    holds) and one page per results Markdown file."""
    pages = {}
    for md in sorted(RESULTS.glob("*.md")):
        pages[f"benchmarks/{md.stem}.md"] = _links_to_plain(md.read_text())
    index = ["# Benchmarks", "",
             "Each benchmark is a script in `benchmarks/` that answers one question and writes "
             "its figures to `benchmarks/results/NAME.md` (and `.json`), starting with the "
             "command, the commit and the date that produced them. The tables below say what "
             "each results file holds; its page shows the file as it was written. The guide "
             "pages quote their figures.", ""]
    for name, question, rows in _benchmarks():
        index += [f"## {name}", "", question, "", "| results | what it holds |", "|---|---|"]
        index += [f"| [`{stem}`]({stem}.md) | {what} |" for stem, what in rows]
        index.append("")
    index += ["## Running them", "",
              "`benchmarks/README.md` in the repository lists every script, its options and "
              "the command behind each results file.", ""]
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
    # the benchmarks: the overview, then each benchmark's main results page by its name
    bench = [{"Overview": "benchmarks/index.md"}]
    bench += [{name: f"benchmarks/{rows[0][0]}.md"} for name, _, rows in _benchmarks()
              if name != "Other results"]
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
