"""The numbers the README and the docs quote are the ones the code gives now.

Every console block in README.md and docs/*.md that follows a ``hdsim demo`` or
``hdsim simulate …`` command is re-run here (in a temporary folder, the scenario paths
pointing into this checkout) and each ``name  number`` line it shows is compared with the
same line of the fresh output, to the digits the page prints. So is every command typed in
a console block (``$ hdsim …``) with the lines the page shows under it: a figure to its
digits, a JSON object key by key, any other line (an error, a table) as printed. The Python
example of the README and the home page (its ``# … arcmin`` comment) is run too. A change
to the physics that moves a quoted figure fails here until the page is updated: a page
cannot go stale.
"""

from __future__ import annotations

import re
import shutil
from pathlib import Path

import pytest

ROOT = Path(__file__).resolve().parents[1]
PAGES = [ROOT / "README.md", *sorted((ROOT / "docs").glob("*.md"))]
BLOCK = re.compile(r"```bash\n(?:pip install [^\n]*&& )?(hdsim (?:demo|simulate)[^\n]*)\n```\s*(?:\n[^`][^\n]*)*?\n```console\n(.*?)```",
                   re.DOTALL)
#: a quoted figure: a label (words, or a metric name) and a number, at the start of a line
FIGURE = re.compile(r"^\s+([A-Za-z][^\n]*?)\s{2,}(-?\d[\d.]*(?:e[+-]?\d+)?)(?=\s|$)", re.MULTILINE)


def _quoted_blocks():
    out = []
    for page in PAGES:
        for m in BLOCK.finditer(page.read_text(encoding="utf-8")):
            if "--json" not in m.group(1):
                out.append(pytest.param(m.group(1), m.group(2), id=f"{page.name}: {m.group(1)}"))
    return out


#: the simulator's own resolution: a dynamic run's metrics move by a few 1e-6 relative when
#: round-off changes its adaptive steps (a torsion at the tip by 3e-6 when the dead zone's
#: softplus moved to `math`), so a quoted number sitting on a rounding boundary may flip
RESOLUTION = 1e-5


def _agrees(quoted: str, value: float) -> bool:
    """``value`` printed to the digits of ``quoted`` gives ``quoted`` (half a unit of its last
    digit), within the simulator's `RESOLUTION`."""
    mantissa = quoted.split("e")[0]
    decimals = len(mantissa.split(".")[1]) if "." in mantissa else 0
    exponent = int(quoted.split("e")[1]) if "e" in quoted else 0
    digit = 0.5 * 10.0 ** (exponent - decimals) * (1 + 1e-9)
    return abs(value - float(quoted)) <= digit + RESOLUTION * abs(value)


def _share_runs(monkeypatch, shared: list) -> None:
    """The verbs' runs of the models and scenarios of ``shared`` are those (the same model and
    scenario, checked); any other run is made anew."""
    from hdsim.cli import demo, simulate
    from hdsim.scenarios.run import run_scenario

    def run(model, scenario, evaluator="dynamic"):
        for done in shared:
            if (model.name == done.model.name and model.params() == done.model.params()
                    and scenario.data == done.scenario.data and evaluator == "dynamic"):
                return done
        return run_scenario(model, scenario, evaluator=evaluator)

    monkeypatch.setattr(demo, "run_scenario", run)
    monkeypatch.setattr(simulate, "run_scenario", run)


@pytest.fixture
def shared_default_runs(monkeypatch, default_lost_motion_run, default_stiffness_run):
    """The session's runs of the default unit's shipped lost-motion and stiffness scenarios."""
    _share_runs(monkeypatch, [default_lost_motion_run, default_stiffness_run])


@pytest.mark.parametrize("command, shown", _quoted_blocks())
def test_a_console_block_of_the_docs_is_what_the_command_prints(command, shown, cli, tmp_path, shared_default_runs):
    args = [a.replace("scenarios/", str(ROOT / "scenarios") + "/") for a in command.split()[1:]]
    code, out, err = cli(*args, cwd=tmp_path)
    assert code == 0, err
    fresh = {label.strip(): float(number) for label, number in FIGURE.findall(out)}
    quoted = FIGURE.findall(shown)
    assert quoted, f"no figure found in the block of {command!r}"
    for label, number in quoted:
        label = label.strip()
        assert label in fresh, f"{command}: '{label}' is not printed any more"
        assert _agrees(number, fresh[label]), f"{command}: the page says {label} {number}, it prints {fresh[label]:.6g}"


# --------------------------------------------------------------------------- commands typed in console blocks
CONSOLE = re.compile(r"```console\n(.*?)```", re.DOTALL)
#: a command typed at the prompt and the lines shown under it, up to the next prompt
TYPED = re.compile(r"^\$ (hdsim\b[^\n]*)\n((?:(?!\$ )[^\n]*\n)*)", re.MULTILINE)
#: a run time, which no two runs share: "(4.9 s)", "(2600 elements, …, 0.11 s)"
RUN_TIME = re.compile(r"\b\d+(?:\.\d+)? s\)")
BENCH = "docs/figures/tutorial_bench.csv"


def _typed_commands():
    """Every ``$ hdsim …`` of a console block that shows what it prints (one shown without
    output, as before a redirection or a long report, quotes nothing)."""
    out = []
    for page in PAGES:
        for block in CONSOLE.finditer(page.read_text(encoding="utf-8")):
            for m in TYPED.finditer(block.group(1)):
                if m.group(2).strip():
                    out.append(pytest.param(page, m.group(1), m.group(2), id=f"{page.name}: $ {m.group(1)}"))
    return out


def _reader_folder(folder: Path, page: Path, command: str) -> None:
    """What the typed commands read, where the page's reader has it: the checkout's scenario
    files, the tutorial's bench file, and a drive file the page shows (``--unit NAME.toml``)."""
    (folder / "scenarios").symlink_to(ROOT / "scenarios")
    (folder / "docs" / "figures").mkdir(parents=True)
    shutil.copy(ROOT / BENCH, folder / BENCH)
    for name in re.findall(r"--unit (\S+\.toml)", command):
        shown = re.search(rf"\(`{re.escape(name)}`\):\s*```toml\n(.*?)```", page.read_text(encoding="utf-8"),
                          re.DOTALL)
        assert shown, f"{page.name}: '{command}' reads {name}, which the page does not show"
        (folder / name).write_text(shown.group(1), encoding="utf-8")


def _typed(args, folder, capsys, monkeypatch):
    """``(exit status, stdout, stderr)`` of ``hdsim ARGS`` in ``folder``; argparse's ``--help``
    and its refusals end with SystemExit, which the shell sees as the status."""
    from hdsim.cli import main

    monkeypatch.chdir(folder)
    capsys.readouterr()
    try:
        code = main(args)
    except SystemExit as exc:
        code = exc.code
    printed = capsys.readouterr()
    return code, printed.out, printed.err


def _same_json(where: str, shown: list[str], out: str) -> None:
    """A page's one-line JSON object, cut short with ``...``: the keys it shows are the first
    printed, with the same values, each metric to the digits shown."""
    import json

    assert len(shown) == 1, f"{where}: a JSON example is one line"
    page = json.loads(shown[0].replace(", ...}", "}"), parse_float=str)
    printed = json.loads(out)
    assert list(page) == list(printed)[:len(page)], \
        f"{where}: the page shows keys {list(page)}, it prints {list(printed)}"
    for key, value in page.items():
        if key != "metrics":
            assert value == printed[key], f"{where}: the page says {key} {value!r}, it prints {printed[key]!r}"
            continue
        assert list(value) == list(printed[key]), \
            f"{where}: the page shows metrics {list(value)}, it prints {list(printed[key])}"
        for name, number in value.items():
            assert _agrees(number, printed[key][name]), \
                f"{where}: the page says {name} {number}, it prints {printed[key][name]:.6g}"


def _same_lines(where: str, shown: list[str], printed: list[str], figures: bool) -> None:
    """The lines a page shows are the lines printed (stdout and stderr, in any order: one
    terminal shows both), run times aside; with ``figures`` a ``name  number`` line agrees to
    the digits shown (`_agrees`), any other line is printed as shown."""
    def split(lines):
        numbers, rest = {}, []
        for line in (RUN_TIME.sub("# s)", line) for line in lines if line.strip()):
            figure = FIGURE.match(line) if figures else None
            if figure:
                numbers[figure.group(1).strip()] = figure.group(2)
            else:
                rest.append(line)
        return numbers, sorted(rest)

    (quoted, page_lines), (fresh, lines) = split(shown), split(printed)
    assert page_lines == lines, "\n".join(
        [f"{where}: the page shows lines the command does not print, or misses some:"]
        + [f"  page only:    {line}" for line in page_lines if line not in lines]
        + [f"  printed only: {line}" for line in lines if line not in page_lines])
    assert list(quoted) == list(fresh), f"{where}: the page shows figures {list(quoted)}, it prints {list(fresh)}"
    for label, number in quoted.items():
        assert _agrees(number, float(fresh[label])), \
            f"{where}: the page says {label} {number}, it prints {fresh[label]}"


@pytest.mark.parametrize("page, command, shown", _typed_commands())
def test_a_command_typed_in_a_console_block_prints_what_the_page_shows(page, command, shown, tmp_path, capsys,
                                                                         monkeypatch):
    if "--fe" in command.split():
        pytest.importorskip("skfem")
    monkeypatch.setenv("COLUMNS", "80")  # argparse wraps --help to the terminal's width
    _reader_folder(tmp_path, page, command)
    code, out, err = _typed(command.split()[1:], tmp_path, capsys, monkeypatch)
    lines = [line for line in shown.splitlines() if line.strip()]
    refused = any(": error: " in line for line in lines)
    where = f"{page.name}, '$ {command}'"
    assert code == (2 if refused else 0), f"{where}: exit status {code}: {err}"
    if lines[0].startswith("{"):
        _same_json(where, lines, out)
    else:
        _same_lines(where, lines, (out + err).splitlines(), figures=command.split()[1] in ("demo", "simulate"))


def test_the_typed_commands_are_found():
    verbs = {p.values[1].split()[1] for p in _typed_commands()}
    assert {"--help", "units", "compliance", "simulate", "fit", "diagnose", "sobol"} <= verbs, verbs
    typed = {p.values[1] for p in _typed_commands()}
    assert "hdsim simulate scenarios/reversal.toml" in typed
    # the fit and the diagnosis of the tutorial's bench file, on docs/cli.md
    assert {f"hdsim {verb} {BENCH} --effects friction" for verb in ("fit", "diagnose")} <= typed


def test_the_python_example_prints_what_its_comment_says():
    import hdsim

    drive = hdsim.load_unit("CSG-25-100").with_updates({"flexspline.h_c": 0.6e-3})
    value = hdsim.run_scenario(drive, "lost_motion").metric("lost_motion_arcmin")
    for page in (ROOT / "README.md", ROOT / "docs" / "index.md"):
        comment = re.search(r'print\(run\.metric\("lost_motion_arcmin"\)\)\s+# ([\d.]+) arcmin', page.read_text())
        assert comment, page
        assert _agrees(comment.group(1), value), f"{page.name} says {comment.group(1)}, the example prints {value:.4g}"


def test_every_figure_script_is_listed_on_the_home_page():
    home = (ROOT / "docs" / "index.md").read_text(encoding="utf-8")
    scripts = sorted(p.name for p in (ROOT / "docs").glob("make_*.py"))
    assert scripts and all(f"python docs/{name}" in home for name in scripts), scripts


# --------------------------------------------------------------------------- tables of the physics page
PHYSICS = ROOT / "docs" / "physics.md"
#: the five-unit table's columns: (metric of `hdsim demo --json`, or the elastic span)
UNIT_COLUMNS = ("elastic_lost_motion_arcmin", "lost_motion_arcmin", "lost_motion_centre_line_arcmin",
                "hysteresis_loss_arcmin", "torsion_at_rated_arcmin")


def _table_after(text: str, marker: str) -> list[list[str]]:
    """The cells of the first markdown table after ``marker`` (header and rule left out)."""
    start = text.index(marker)
    rows = []
    for line in text[start:].splitlines()[1:]:
        if line.startswith("|"):
            rows.append([cell.strip() for cell in line.strip("|").split("|")])
        elif rows:
            break
    return rows[2:]


def _demo_metrics(run_lost_motion, run_stiffness, unit) -> dict:
    from hdsim.units import rad_to_arcmin

    metrics = {k: float(v[0]) for run in (run_lost_motion, run_stiffness) for k, v in run.metrics.items()}
    metrics["elastic_lost_motion_arcmin"] = rad_to_arcmin(0.08 * float(unit.drive.rated_torque)
                                                           / unit.provenance["catalog"]["K1"])
    return metrics


def test_the_physics_pages_table_of_the_default_unit_is_what_the_demo_gives(default_lost_motion_run,
                                                                              default_stiffness_run):
    from hdsim.model.catalog import load_unit

    metrics = _demo_metrics(default_lost_motion_run, default_stiffness_run, load_unit())
    rows = _table_after(PHYSICS.read_text(encoding="utf-8"), "The default CSG-25-100 gives (`hdsim demo --json`)")
    assert len(rows) == 7
    for name, quoted, _ in rows:
        value = quoted.replace(" ", "")  # a thin space groups thousands: 30 497
        assert _agrees(value, metrics[name.strip("`")]), (name, quoted, metrics[name.strip("`")])
    five = _table_after(PHYSICS.read_text(encoding="utf-8"), "The same holds for all five units")
    row = next(r for r in five if r[0] == "CSG-25-100")
    for column, quoted in zip(UNIT_COLUMNS, row[1:]):
        assert _agrees(quoted, metrics[column]), (column, quoted, metrics[column])


@pytest.mark.slow
def test_the_physics_pages_table_of_the_five_units_is_what_the_demo_gives():
    from hdsim.model.catalog import load_unit
    from hdsim.scenarios.run import run_scenario

    five = _table_after(PHYSICS.read_text(encoding="utf-8"), "The same holds for all five units")
    assert len(five) == 5
    for row in five:
        unit = load_unit(row[0])
        metrics = _demo_metrics(run_scenario(unit, "lost_motion"), run_scenario(unit, "stiffness"), unit)
        for column, quoted in zip(UNIT_COLUMNS, row[1:]):
            assert _agrees(quoted, metrics[column]), (row[0], column, quoted, metrics[column])


JSON_BLOCK = re.compile(r"```bash\n(hdsim simulate [^\n]*--json)\n```\s*```(?:console|json)\n(.*?)```", re.DOTALL)


def _json_blocks():
    return [pytest.param(m.group(1), m.group(2), id=f"{page.name}: {m.group(1)}")
            for page in PAGES for m in JSON_BLOCK.finditer(page.read_text(encoding="utf-8"))]


@pytest.mark.parametrize("command, shown", _json_blocks())
def test_a_json_block_of_the_docs_is_what_the_command_prints(command, shown, cli, tmp_path, monkeypatch, request):
    """The object a page shows for ``hdsim simulate … --json`` (line breaks added, digits cut)
    has the keys the command prints, the same files, and every metric to the digits shown."""
    import json

    # the session's run of the contract scenario only where the page runs it: a worker that does
    # not need it does not wait for it (the other block's model is no session run's)
    _share_runs(monkeypatch, [request.getfixturevalue("ke_run")] if "kinematic_error" in command else [])
    args = [a.replace("scenarios/", str(ROOT / "scenarios") + "/") for a in command.split()[1:]]
    code, out, err = cli(*args, cwd=tmp_path)
    assert code == 0, err
    printed, page = json.loads(out), json.loads(shown)
    assert list(page) == list(printed), f"{command}: the page shows keys {list(page)}, it prints {list(printed)}"
    assert page["files"] == printed["files"] and page["result"] == printed["result"], command
    assert list(page["metrics"]) == list(printed["metrics"]), command
    quoted = dict(re.findall(r'"(\w+)": (-?\d[\d.]*)', shown.split('"metrics":', 1)[1].split("}", 1)[0]))
    for name, number in quoted.items():
        assert _agrees(number, printed["metrics"][name]), \
            f"{command}: the page says {name} {number}, it prints {printed['metrics'][name]:.6g}"


def test_both_json_blocks_are_found():
    assert len(_json_blocks()) == 2