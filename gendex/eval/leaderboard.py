"""The leaderboard: result files under ``leaderboard/<suite>/``, validated, rendered as a static site and Markdown.

A result file is a JSON object: ``method``, ``authors``, ``code`` (a link), ``policy_kind`` (one of
:data:`KINDS`), ``training_data`` (what it learned from, or "none"), ``date`` (YYYY-MM-DD), ``policy`` (the
``--policy`` spec it was run with), ``sees_simulator_state`` (whether the policy reads the simulator's object state
besides cameras and joints) and ``eval_info``: what ``gendex eval`` wrote, in lerobot 0.4's layout or, for results
filed before it, the earlier one (:mod:`gendex.eval.eval_info` reads and checks both). :func:`load_entries` refuses a
file with a missing or unknown field, another suite's result, or numbers that do not add up; a result whose suite
hash differs from the suite file's is kept but marked stale (the suite changed since). A result must record the digest
of each task's files (``eval_info["task_digests"]``, written by ``gendex eval``), and each must equal the suite's
(the task version as committed, :func:`~gendex.eval.suite.suite_task_digests`): :class:`ResultDigestError` otherwise,
so a score made on a copy with another reward or spec under a suite's task id is refused.

:func:`build_site` writes ``index.html`` and a page per suite (newest suite versions first): a table sortable by any
column (click its header), each method's success with its 95 % Wilson interval, a column per skill (the episodes of
the tasks exercising it, from the result's task groups), and a per-task breakdown that opens under its row; links to
the result files (copied next to the pages) and to videos where a result has them. :func:`markdown` gives the same
tables for ``docs/leaderboard.md``.
"""

from __future__ import annotations

import html
import re
import shutil
from dataclasses import dataclass, field, replace
from pathlib import Path

import dacite

from gendex.eval.eval_info import Summary, skill_rates, summary
from gendex.eval.eval_info import problems as eval_problems
from gendex.eval.metrics import wilson
from gendex.eval.suite import Suite, load_suite, suite_task_digests
from gendex_envs.errors import GenDexError
from gendex_envs.typed_yaml import parse_json_bounded

REPO_ROOT = Path(__file__).resolve().parents[2]
LEADERBOARD_DIR = REPO_ROOT / "leaderboard"
KINDS = ("baseline", "oracle", "imitation", "reinforcement", "other")


MAX_RESULT_BYTES = 8_000_000
MAX_RESULT_NODES = 200_000
"""Bounds of a result file, checked while it is parsed (the committed ones: at most 160 KB; the library suite's 43
tasks x 5 episodes, with every episode's record)."""


class LeaderboardError(GenDexError, ValueError):
    """A result file is malformed, or belongs to another suite."""


class ResultDigestError(LeaderboardError):
    """A result was evaluated on task files other than the suite's (or does not say which): its task digests differ
    from the committed versions'."""


@dataclass(frozen=True)
class Entry:
    method: str
    authors: str
    code: str
    policy_kind: str
    training_data: str
    date: str
    policy: str
    eval_info: dict
    sees_simulator_state: bool
    """Whether the policy reads the simulator's state beyond the robot's own (object poses, the planner's world):
    such a method is not comparable with one that sees only cameras and joint state."""
    notes: str = ""
    file: str = field(default="")
    """The result file's name (set when loaded)."""
    stale: bool = False
    """True when it was evaluated on another version of the suite file (its hash differs)."""

    @property
    def summary(self) -> Summary:
        return summary(self.eval_info)

    @property
    def aggregated(self) -> dict:
        """``episodes``, ``successes``, ``pc_success``, ``wilson95`` over the whole result (either layout)."""
        return self.summary.overall

    @property
    def per_task(self) -> dict:
        """Task -> ``episodes``, ``successes``, ``pc_success``, ``wilson95``, ``pc_success_once``, ``mean_length``,
        ``seeds``, ``group`` (either layout)."""
        return self.summary.per_task

    @property
    def skills(self) -> dict[str, tuple[int, int]]:
        """Skill -> (successes, episodes) over the tasks exercising it (results that record task groups)."""
        return skill_rates(self.summary)


def _check(e: Entry, suite: Suite, path: Path) -> list[str]:
    problems = []
    if e.policy_kind not in KINDS:
        problems.append(f"policy_kind {e.policy_kind!r} is not one of {list(KINDS)}")
    if not re.fullmatch(r"\d{4}-\d{2}-\d{2}", e.date):
        problems.append(f"date {e.date!r} is not YYYY-MM-DD")
    if not e.code.startswith(("https://", "http://", "./", "../")):
        problems.append(f"code {e.code!r} is not a link")
    info = e.eval_info
    problems += eval_problems(info)
    if problems:
        return problems
    if info["suite"].get("name") != suite.name:
        problems.append(f"it is a result on suite {info['suite'].get('name')!r}, filed under {suite.name!r}")
    tasks = summary(info).per_task
    unknown = sorted(set(tasks) - set(suite.tasks))
    if unknown:
        problems.append(f"tasks {unknown} are not in suite {suite.name}")
    missing = sorted(set(suite.tasks) - set(tasks))
    if missing:
        problems.append(f"tasks {missing} of suite {suite.name} have no result: a result covers every task")
    return problems


def _check_digests(e: Entry, want: dict[str, str], path: Path) -> None:
    got = e.eval_info.get("task_digests")
    if not isinstance(got, dict):
        raise ResultDigestError(f"{path}: eval_info has no 'task_digests': the digest of each task's files, which "
                                "gendex eval records; without it the result cannot show it ran on the suite's tasks")
    bad = [f"{task} ran on files with digest {str(got.get(task))[:64]}, the suite's (committed) version has "
           f"{want[task]}" for task in e.per_task if got.get(task) != want[task]]
    if bad:
        raise ResultDigestError(f"{path}: {'; '.join(bad)}. A result on other task files than the suite's (a changed "
                                "or replaced task folder) is not a result on the suite")


def load_entries(suite_name: str, root: Path = LEADERBOARD_DIR) -> list[Entry]:
    """Every result of ``leaderboard/<suite>/`` (sorted best first by the suite's metric), validated."""
    suite = load_suite(suite_name)
    want = suite_task_digests(suite)
    out = []
    for path in sorted((root / suite_name).glob("*.json")):
        try:
            raw = parse_json_bounded(path.read_bytes(), str(path), max_bytes=MAX_RESULT_BYTES,
                                     max_nodes=MAX_RESULT_NODES)
            entry = dacite.from_dict(Entry, {**raw, "file": path.name}, config=dacite.Config(strict=True))
        except (ValueError, dacite.DaciteError, TypeError) as exc:
            raise LeaderboardError(f"{path}: {exc}") from exc
        problems = _check(entry, suite, path)
        if problems:
            raise LeaderboardError(f"{path}: " + "; ".join(problems))
        _check_digests(entry, want, path)
        if entry.eval_info["suite"]["hash"] != suite.hash:
            entry = replace(entry, stale=True)
        out.append(entry)
    return sorted(out, key=lambda e: -e.aggregated["pc_success"])


def _newest_first(name: str) -> tuple[int, str]:
    m = re.search(r"-v(\d+)$", name)
    return (-int(m.group(1)) if m else 0, name)


def suites_with_results(root: Path = LEADERBOARD_DIR) -> list[str]:
    """The suites with results, the newest suite versions first (``gendex-ref-v2`` before ``gendex-lib-v1``)."""
    if not root.is_dir():
        return []
    return sorted((p.name for p in root.iterdir() if p.is_dir() and any(p.glob("*.json"))), key=_newest_first)


# --------------------------------------------------------------------------------------------- rendering
_STYLE = """body{font-family:system-ui,sans-serif;margin:2em auto;max-width:1100px;color:#222}
table{border-collapse:collapse;width:100%}th,td{padding:.35em .6em;border-bottom:1px solid #ddd;text-align:left}
th{cursor:pointer;background:#f4f4f4;user-select:none}
th.sorted-asc::after{content:" ▲"}th.sorted-desc::after{content:" ▼"}
tr.breakdown{display:none;background:#fafafa}tr.breakdown.open{display:table-row}button.toggle{cursor:pointer}
.ci{color:#666;font-size:.9em}.stale{color:#a60}.bar{display:inline-block;height:.7em;background:#4a7}"""

_SCRIPT = """document.querySelectorAll('table.board').forEach(function (table) {
  table.querySelectorAll('th[data-key]').forEach(function (th, col) {
    th.addEventListener('click', function () {
      var asc = !th.classList.contains('sorted-asc');
      table.querySelectorAll('th').forEach(function (h) { h.classList.remove('sorted-asc', 'sorted-desc'); });
      th.classList.add(asc ? 'sorted-asc' : 'sorted-desc');
      var body = table.tBodies[0];
      var rows = Array.prototype.slice.call(body.querySelectorAll('tr.entry'));
      rows.sort(function (a, b) {
        var x = a.cells[col].dataset.value, y = b.cells[col].dataset.value;
        var nx = parseFloat(x), ny = parseFloat(y);
        var c = (!isNaN(nx) && !isNaN(ny)) ? nx - ny : String(x).localeCompare(String(y));
        return asc ? c : -c;
      });
      rows.forEach(function (r) { body.appendChild(r); body.appendChild(document.getElementById(r.dataset.detail)); });
    });
  });
});
document.querySelectorAll('button.toggle').forEach(function (b) {
  b.addEventListener('click', function () {
    var row = document.getElementById(b.dataset.detail);
    row.classList.toggle('open');
    b.textContent = row.classList.contains('open') ? 'hide tasks' : 'per task';
  });
});"""


def _e(x) -> str:
    return html.escape(str(x), quote=True)


def _page(title: str, body: str) -> str:
    return (f'<!DOCTYPE html>\n<html lang="en"><head><meta charset="utf-8"><title>{_e(title)}</title>'
            f"<style>{_STYLE}</style></head><body>\n{body}\n<script>{_SCRIPT}</script></body></html>\n")


def _skills(entries: list[Entry]) -> list[str]:
    """The skills the results record, in the order their tasks first name them."""
    return list(dict.fromkeys(k for e in entries for k in e.skills))


def _skill_cell(e: Entry, skill: str) -> tuple[str, str]:
    if skill not in e.skills:
        return "-1", "—"
    k, n = e.skills[skill]
    lo, hi = wilson(k, n)
    return f"{100.0 * k / n:.4f}", (f'{100.0 * k / n:.0f} <span class="ci">[{100 * lo:.0f}, {100 * hi:.0f}]</span>')


def _suite_page(suite: Suite, entries: list[Entry]) -> str:
    skills = _skills(entries)
    cols = [("method", "Method"), ("kind", "Kind"), ("state", "Sees sim state"),
            ("success", f"Success ({suite.metric}, %)"), ("once", "Success once (%)"),
            *[(f"skill-{k}", k.replace("_", " ")) for k in skills],
            ("episodes", "Episodes"), ("length", "Mean length"), ("data", "Training data"), ("date", "Date")]
    head = "".join(f'<th data-key="{_e(k)}">{_e(v)}</th>' for k, v in cols) + "<th>Details</th>"
    rows = []
    for i, e in enumerate(entries):
        a = e.aggregated
        lo, hi = a["wilson95"]
        once = sum(t["pc_success_once"] * t["episodes"] for t in e.per_task.values()) / max(1, a["episodes"])
        length = sum(t["mean_length"] * t["episodes"] for t in e.per_task.values()) / max(1, a["episodes"])
        stale = ' <span class="stale" title="evaluated on another version of the suite">(stale)</span>' \
            if e.stale else ""
        state = "yes" if e.sees_simulator_state else "no"
        cells = [(e.method, f'<a href="{_e(e.code)}">{_e(e.method)}</a>{stale}<br><span class="ci">{_e(e.authors)}'
                            f"</span>"),
                 (e.policy_kind, _e(e.policy_kind)), (state, state),
                 (f"{a['pc_success']:.4f}", f'{a["pc_success"]:.1f} <span class="ci">[{lo:.1f}, {hi:.1f}]</span>'),
                 (f"{once:.4f}", f"{once:.1f}"), *[_skill_cell(e, k) for k in skills],
                 (a["episodes"], a["episodes"]), (f"{length:.4f}", f"{length:.0f}"),
                 (e.training_data, _e(e.training_data)), (e.date, _e(e.date))]
        tds = "".join(f'<td data-value="{_e(v)}">{h}</td>' for v, h in cells)
        detail = f"detail-{i}"
        tds += (f'<td><button class="toggle" data-detail="{detail}">per task</button> '
                f'<a href="results/{_e(suite.name)}/{_e(e.file)}">json</a></td>')
        rows.append(f'<tr class="entry" data-detail="{detail}">{tds}</tr>')
        task_rows = "".join(
            f"<tr><td>{_e(t)}</td><td>{_e(r['group'] or '')}</td><td>{r['successes']}/{r['episodes']}</td>"
            f"<td>{r['pc_success']:.1f} "
            f'<span class="ci">[{r["wilson95"][0]:.1f}, {r["wilson95"][1]:.1f}]</span> '
            f'<span class="bar" style="width:{r["pc_success"]:.0f}px"></span></td>'
            f"<td>{r['pc_success_once']:.1f}</td><td>{r['mean_length']:.0f}</td></tr>"
            for t, r in e.per_task.items())
        videos = "".join(f'<a href="{_e(v)}">{_e(Path(v).name)}</a> ' for v in _video_paths(e.eval_info))
        rows.append(f'<tr class="breakdown" id="{detail}"><td colspan="{len(cols) + 1}"><table class="tasks">'
                    f"<tr><th>Task</th><th>Skills</th><th>Successes</th><th>Success (%) [95 % CI]</th>"
                    f"<th>Once (%)</th><th>Mean length</th></tr>{task_rows}</table>{videos}</td></tr>")
    body = (f'<p><a href="index.html">All suites</a></p><h1>{_e(suite.name)}</h1><p>{_e(suite.description)}</p>'
            f"<p>{len(suite.tasks)} tasks, {suite.episodes} episodes each on seeds {suite.seed}.., metric "
            f"<code>{_e(suite.metric)}</code>, suite file SHA-256 <code>{suite.hash[:16]}…</code>. Intervals are "
            f"95 % Wilson score intervals; a skill's column pools the episodes of the tasks exercising it. "
            f"<em>Sees sim state</em>: the policy reads the simulator's object state, not only cameras and joints. "
            f"Click a column to sort.</p>"
            f'<table class="board" id="board"><thead><tr>{head}</tr></thead><tbody>{"".join(rows)}</tbody></table>')
    return _page(f"GenDex leaderboard: {suite.name}", body)


def _video_paths(info: dict) -> list[str]:
    if "overall" in info:
        return list(info["overall"].get("video_paths", []))
    return list(info.get("video_paths", []))


def build_site(out: Path, root: Path = LEADERBOARD_DIR) -> list[Path]:
    """Write the static site to ``out``: ``index.html``, ``<suite>.html``, ``results/<suite>/*.json``."""
    out.mkdir(parents=True, exist_ok=True)
    written, items = [], []
    for name in suites_with_results(root):
        suite, entries = load_suite(name), load_entries(name, root)
        (out / "results" / name).mkdir(parents=True, exist_ok=True)
        for e in entries:
            shutil.copy2(root / name / e.file, out / "results" / name / e.file)
        page = out / f"{name}.html"
        page.write_text(_suite_page(suite, entries))
        written.append(page)
        best = entries[0] if entries else None
        items.append(f'<li><a href="{_e(name)}.html">{_e(name)}</a>: {len(suite.tasks)} tasks, {len(entries)} '
                     f"results" + (f"; best {_e(best.method)} {best.aggregated['pc_success']:.1f} %" if best else "")
                     + "</li>")
    index = out / "index.html"
    index.write_text(_page("GenDex leaderboard", "<h1>GenDex leaderboard</h1><p>Policies on the GenDex benchmark "
                                                 "suites (<code>gendex eval</code>).</p><ul>" + "".join(items) +
                           "</ul>"))
    return [index, *written]


def _episodes(e: Entry, suite: Suite) -> str:
    """Episodes of a result; with the count per task when it ran fewer than the suite's or only some tasks."""
    n = e.aggregated["episodes"]
    per = sorted({t["episodes"] for t in e.per_task.values()})
    if per == [suite.episodes] and len(e.per_task) == len(suite.tasks):
        return str(n)
    each = f"{per[0]}" if len(per) == 1 else f"{per[0]}-{per[-1]}"
    return f"{n} ({each} per task, {len(e.per_task)} of {len(suite.tasks)} tasks)"


def markdown(root: Path = LEADERBOARD_DIR) -> str:
    """``docs/leaderboard.md``: a table per suite, best first, with intervals and a per-task table."""
    lines = ["# Leaderboard", "",
             "Written by `gendex leaderboard build` from the result files in [`leaderboard/`](../leaderboard). Success "
             "is the suite's metric (`success_at_end`) in percent with its 95 % Wilson interval; the rate of "
             "episodes that succeeded at any step (`success_once`) is beside it. `gendex eval --suite NAME --policy "
             "SPEC` makes a result; see [the benchmark](benchmark.md). *Sees sim state*: the policy reads the "
             "simulator's object state (poses, the planner's world), not only cameras and joint state; compare like "
             "with like. Suites are listed newest version first.", ""]
    for name in suites_with_results(root):
        suite, entries = load_suite(name), load_entries(name, root)
        lines += [f"## {name}", "", suite.description, "",
                  f"{len(suite.tasks)} tasks × {suite.episodes} episodes, seeds {suite.seed}.., suite SHA-256 "
                  f"`{suite.hash[:16]}…`.", "",
                  "| method | kind | sees sim state | success % [95 % CI] | once % | episodes | training data | "
                  "policy |",
                  "|---|---|---|---|---|---|---|---|"]
        for e in entries:
            a = e.aggregated
            once = sum(t["pc_success_once"] * t["episodes"] for t in e.per_task.values()) / max(1, a["episodes"])
            lines.append(f"| {e.method}{' (stale)' if e.stale else ''} | {e.policy_kind} | "
                         f"{'yes' if e.sees_simulator_state else 'no'} | {a['pc_success']:.1f} "
                         f"[{a['wilson95'][0]:.1f}, {a['wilson95'][1]:.1f}] | {once:.1f} | {_episodes(e, suite)} | "
                         f"{e.training_data} | `{e.policy}` |")
        skills = _skills(entries)
        if skills:
            lines += ["", "Per skill (success %, the episodes of the tasks exercising it):", "",
                      "| method | " + " | ".join(k.replace("_", " ") for k in skills) + " |",
                      "|---|" + "---|" * len(skills)]
            lines += [f"| {e.method} | " + " | ".join(_skill_cell(e, k)[1].split(" <")[0] for k in skills) + " |"
                      for e in entries]
        notes = [f"- **{e.method}**: {e.notes}" for e in entries if e.notes]
        if notes:
            lines += ["", *notes]
        tasks = list(suite.tasks)
        lines += ["", "Per task (success %, 95 % CI):", "", "| task | " + " | ".join(e.method for e in entries) + " |",
                  "|---|" + "---|" * len(entries)]
        for t in tasks:
            cells = [f"{e.per_task[t]['pc_success']:.0f} [{e.per_task[t]['wilson95'][0]:.0f}, "
                     f"{e.per_task[t]['wilson95'][1]:.0f}]" if t in e.per_task else "—" for e in entries]
            lines.append(f"| `{t}` | " + " | ".join(cells) + " |")
        lines.append("")
    return "\n".join(lines) + "\n"


__all__ = ["KINDS", "LEADERBOARD_DIR", "Entry", "LeaderboardError", "ResultDigestError", "build_site", "load_entries",
           "markdown", "suites_with_results"]
