"""The tutorial (docs/tutorial.md), the how-to guides (docs/howto-*.md) and the README's tour run
as written, so none can go stale.

The runner takes every ```sh block of a page in order and runs it with bash (``-e -o
pipefail``) in one scratch folder holding a copy of ``designs/``, ``examples/`` and
``tests/data/``, as a user runs them from a clone; ``pixelkit`` and ``python`` there are this
interpreter. HTML comments right above a block (invisible on the site) say what it promises:
``<!-- exit: 0 1 -->`` its allowed exit statuses (default 0; verify and the revision diff exit 1
on a failing specification, which the tutorial explains); ``<!-- creates: PATH ... -->`` files it
must leave; ``<!-- expect: REGEX -->`` what its output (stdout and stderr) must hold (the how-to's diagnosis names
the effect the example's virtual silicon was made with); ``<!-- slow -->`` a block that takes
minutes (DRC, sign-off, the reports); ``<!-- parse-only -->`` a block never run;
``<!-- background: HOST:PORT -->`` a block that starts servers (the Dask how-to's scheduler and
workers): run in the background on a free port in place of the page's, waited for until it accepts
connections, ended after the page's walk. A ```text block right after a block is what the page says it prints: every line of it
must be printed, in order, with the same numbers at the digits quoted (``docsite/outputs.py``;
``<!-- vary: REGEX -->`` above the text block names a line whose numbers change from run to run);
with ``PIXELKIT_DOCS_REWRITE=1`` the lines whose numbers moved are rewritten into the page from
the output instead of failing. Every page's whole walk is ``slow`` (``python -m pytest -m slow tests/test_tutorial.py``:
the tutorial 64 s, the how-tos 130 s on a warm cache); by default the quick blocks run and the slow blocks'
``pixelkit`` command lines are parsed by the real click commands in the folder the quick blocks
left (a renamed command or option, a bad value or a design file the page never made fails),
without running them. Independent of the code under test: what is checked is what the page
promises the reader, parsed from the page itself. The simulation cache is the test session's, so
blocks that repeat another test's work are served from it. The other pages' ```sh commands are
parsed (and run when marked ``<!-- run -->``: a quick command whose output a reference page
reads), and every inline `pixelkit ...` mention in the docs and the README must name a command
and options the kit has.
"""
import os
import re
import shlex
import shutil
import subprocess
import sys
from pathlib import Path

import click
import pytest

from conftest import ROOT, wait_for

sys.path.insert(0, str(ROOT))
from docsite import outputs  # noqa: E402

BLOCK = re.compile(r"((?:<!--[^\n]*-->\n)*)```sh\n(.*?)\n```(?:\n\n((?:<!--[^\n]*-->\n)*)```text\n(.*?)\n```)?", re.S)


def sh_blocks(text: str) -> list[dict]:
    """[{code, exit: set of allowed statuses, creates: [paths], slow, parse_only, expect: [regex],
    output: the ```text block right after it or None, vary: [regex]}]
    of the page's ```sh blocks."""
    out = []
    for m in BLOCK.finditer(text):
        notes = m.group(1)
        status = re.search(r"<!--\s*exit:\s*([\d ]+)-->", notes)
        creates = re.search(r"<!--\s*creates:\s*(.+?)\s*-->", notes)
        out.append({"code": m.group(2), "exit": {int(s) for s in status.group(1).split()} if status else {0},
                    "creates": creates.group(1).split() if creates else [],
                    "slow": bool(re.search(r"<!--\s*slow\s*-->", notes)),
                    "parse_only": bool(re.search(r"<!--\s*parse-only\s*-->", notes)),
                    "run": bool(re.search(r"<!--\s*run\s*-->", notes)),
                    "background": (re.findall(r"<!--\s*background:\s*(\S+)\s*-->", notes) or [None])[0],
                    "expect": re.findall(r"<!--\s*expect:\s*(.+?)\s*-->", notes),
                    "output": m.group(4),
                    "vary": re.findall(r"<!--\s*vary:\s*(.+?)\s*-->", m.group(3) or "")})
    return out


def pixelkit_commands(code: str) -> list[list[str]]:
    """The argument lists of the ``pixelkit`` commands of a block (continuation lines joined,
    each command up to a pipe, redirection or ``&&``)."""
    out = []
    for line in code.replace("\\\n", " ").splitlines():
        words = shlex.split(line, comments=True)
        while "pixelkit" in words:
            words = words[words.index("pixelkit") + 1:]
            stop = next((i for i, w in enumerate(words) if w in {"|", ">", ">>", "&&", "||", ";"}), len(words))
            out.append(words[:stop])
            words = words[stop:]
    return out


def parse_command(args: list[str]) -> None:
    """Parse ``pixelkit ARGS`` with the kit's click commands, converting every value (files must
    exist, choices be known), without invoking anything."""
    from pixelkit.cli import register_all
    from pixelkit.cli.common import main
    register_all()
    cmd, parent, rest = main, None, list(args)
    while True:
        ctx = cmd.make_context("pixelkit" if parent is None else cmd.name, rest, parent=parent)
        if not isinstance(cmd, click.Group):
            design = ctx.params.get("design")
            if design and not Path(design).is_file():   # the commands load it when they run
                raise click.UsageError(f"design file {design} does not exist")
            return
        _, cmd, rest = cmd.resolve_command(ctx, ctx._protected_args + ctx.args)
        parent = ctx


def run_blocks(blocks, folder, parse_slow=False, page=None):
    """Run the blocks in order in ``folder``; with ``parse_slow``, a slow block's commands are
    parsed instead of run and the files it promises are stood in for by empty ones, so that a later
    command naming them parses. A block's output is held against the page's text block after it
    (``docsite/outputs.py``); with ``PIXELKIT_DOCS_REWRITE=1`` the text blocks of ``page`` (the
    file the blocks were read from) are rewritten from the output instead."""
    rewrite = os.environ.get("PIXELKIT_DOCS_REWRITE") == "1" and page is not None
    fixes, unfixed, servers, ports = [], [], [], {}
    prelude = (f'pixelkit() {{ "{sys.executable}" -m pixelkit "$@"; }}\n'
               f'python() {{ "{sys.executable}" "$@"; }}\n')
    env = {**os.environ, "PIXELKIT_PROGRESS": "0", "PATH": f"{Path(sys.executable).parent}:{os.environ['PATH']}",
           # the package under test first, as in a user's clone whose root holds it: the clone's partial
           # pixelkit/ folder (gap/silicon_cases only, which file: marks read) would otherwise shadow an
           # editable install as a namespace package (PackageLoader: no report/templates)
           "PYTHONPATH": os.pathsep.join(filter(None, (str(ROOT), os.environ.get("PYTHONPATH"))))}
    env.pop("PIXELKIT_REPORTS", None)
    try:
        for n, b in enumerate(blocks, 1):
            for old, new in ports.items():      # a server the page started on a port of its own: ours
                b = {**b, "code": re.sub(rf"\b{old}\b", new, b["code"])}
            if b["background"] and not (b["parse_only"] or (parse_slow and b["slow"])):
                servers.append(start_server(b, folder, prelude, env, ports))
                continue
            if b["parse_only"] or (parse_slow and b["slow"]):
                with pytest.MonkeyPatch.context() as mp:
                    mp.chdir(folder)
                    for args in pixelkit_commands(b["code"]):
                        try:
                            parse_command(args)
                        except click.ClickException as e:
                            raise AssertionError(f"block {n}: pixelkit {' '.join(args)}: {e.format_message()}") from e
                for f in b["creates"]:
                    (folder / f).parent.mkdir(parents=True, exist_ok=True)
                    (folder / f).touch()
                continue
            p = subprocess.run(["bash", "-e", "-o", "pipefail", "-c", prelude + b["code"]], cwd=folder, env=env,
                               capture_output=True, text=True, timeout=1800)
            output = f"{b['code']}\n--- stderr:\n{p.stderr[-3000:]}\n--- stdout:\n{p.stdout[-2000:]}"
            assert p.returncode in b["exit"], f"block {n} exited {p.returncode} (page: {sorted(b['exit'])}):\n{output}"
            missing = [f for f in b["creates"] if not (folder / f).exists()]
            assert not missing, f"block {n} did not create {missing}:\n{b['code']}"
            for rx in b["expect"]:
                assert re.search(rx, p.stdout + p.stderr), f"block {n} did not print {rx!r}:\n{output}"
            if b.get("output") is not None:
                problems, fixed = outputs.compare(b["output"], p.stdout + p.stderr, b["vary"])
                if problems and rewrite:
                    fixes.append((b["output"], fixed))
                    hand = [f"block {n}: {s}" for s in problems if s.startswith("not printed")]
                    unfixed += hand + ([f"--- block {n} printed:\n{(p.stdout + p.stderr)[-6000:]}"] if hand else [])
                elif problems:
                    raise AssertionError(f"block {n}'s output is not what the page shows "
                                         "(PIXELKIT_DOCS_REWRITE=1 rewrites the numbers):\n  "
                                         + "\n  ".join(problems) + f"\n--- printed:\n{(p.stdout + p.stderr)[-3000:]}")
    finally:
        for proc in servers:
            stop_server(proc)
        if fixes:   # by the block's text, not its place: the page may have changed during the walk
            text = page.read_text()
            for old, fixed in fixes:
                if text.count(f"```text\n{old}\n```") == 1:
                    text = text.replace(f"```text\n{old}\n```", f"```text\n{fixed}\n```")
                else:
                    unfixed.append(f"a block to rewrite is no longer on the page once:\n{old}")
            page.write_text(text)
    assert not unfixed, "lines to rewrite by hand:\n  " + "\n  ".join(unfixed)


def start_server(b, folder, prelude, env, ports):
    """Start a ``<!-- background: HOST:PORT -->`` block (a Dask scheduler and its workers) in a process
    group of its own, on a free port in place of the page's (the port's number is replaced in this and
    the later blocks of the page), and wait until it accepts connections."""
    import socket
    host, port = b["background"].rsplit("/", 1)[-1].rsplit(":", 1)
    with socket.socket() as s:
        s.bind(("127.0.0.1", 0))
        free = str(s.getsockname()[1])
    ports[port] = free
    code = re.sub(rf"\b{port}\b", free, b["code"])
    log = open(folder / f"server-{free}.log", "w")
    proc = subprocess.Popen(["bash", "-c", prelude + code + "\nwait"], cwd=folder, env=env, stdout=log,
                            stderr=subprocess.STDOUT, start_new_session=True)

    def up():
        assert proc.poll() is None, f"the server block exited {proc.returncode}:\n{(folder / log.name).read_text()}"
        with socket.socket() as s:
            return s.connect_ex((host, int(free))) == 0
    wait_for(up, f"the page's server on {host}:{free}", within=300)
    return proc


def stop_server(proc):
    """End the server block's process group (its scheduler and workers), ours alone, and wait until no
    process of the group is left (the shell exits first; its children may still hold the port)."""
    import signal

    def group_gone():   # a live process of the group left (a zombie holds no port: an unreaping init)
        for stat in Path("/proc").glob("[0-9]*/stat"):
            try:
                fields = stat.read_text().rsplit(")", 1)[1].split()
            except OSError:
                continue
            if int(fields[2]) == proc.pid and fields[0] != "Z":
                return False
        return True
    try:
        os.killpg(proc.pid, signal.SIGTERM)
        proc.wait(timeout=60)
    except subprocess.TimeoutExpired:
        os.killpg(proc.pid, signal.SIGKILL)
        proc.wait()
    except ProcessLookupError:
        pass
    try:
        wait_for(group_gone, "the server block's processes to end", within=60)
    except AssertionError:
        os.killpg(proc.pid, signal.SIGKILL)
        wait_for(group_gone, "the server block's processes to end after SIGKILL", within=60)


#: what a clone carries: the pages' inputs, and every file a docs mark reads (record: / file: / input:,
#: held by tests/test_docs_figures.py::test_every_file_a_mark_reads_is_in_the_docs_clone)
CLONE_FOLDERS = ("designs", "examples", "tests/data", "docsite", "docs", "benchmarks/results",
                 "pixelkit/gap/silicon_cases", "pixelkit/gap/surrogates", "pixelkit/tech/builtin")


@pytest.fixture
def clone(tmp_path):
    """What the pages' commands read from a clone: the designs, the examples, the EMVA 1288 test
    data and the docs tooling with the pages it reads (``python -m docsite.figures`` checks every docs
    page and the README, run from the clone's root)."""
    for d in CLONE_FOLDERS:
        shutil.copytree(ROOT / d, tmp_path / d)
    shutil.copy2(ROOT / "README.md", tmp_path / "README.md")
    return tmp_path


HOWTOS = sorted(p.name for p in (ROOT / "docs").glob("howto-*.md") if sh_blocks(p.read_text()))


@pytest.mark.slow
@pytest.mark.parametrize("page", HOWTOS)
def test_howto_runs_as_written(page, clone):
    run_blocks(sh_blocks((ROOT / "docs" / page).read_text()), clone, page=ROOT / "docs" / page)


@pytest.mark.parametrize("page", HOWTOS)
def test_howto_quick_blocks_run_and_slow_commands_parse(page, clone):
    run_blocks(sh_blocks((ROOT / "docs" / page).read_text()), clone, parse_slow=True, page=ROOT / "docs" / page)


def test_example_measurements_are_silicon_case_c1001_unchanged():
    """examples/measured_revA.csv is case c1001 of the SPICE virtual silicon (docs/howto-measurements.md
    states its truth from truth.json); the page's check that the diagnosis names fd_leakage rests on it."""
    import csv
    import json
    cases = [{k: v for k, v in r.items() if k != "case"}
             for r in csv.DictReader(open(ROOT / "pixelkit/gap/silicon_cases/cases.csv")) if r["case"] == "c1001"]
    assert list(csv.DictReader(open(ROOT / "examples/measured_revA.csv"))) == cases
    truth = json.loads((ROOT / "pixelkit/gap/silicon_cases/truth.json").read_text())["c1001"]
    assert truth["effect"] == "fd_leakage" and truth["params"]["i_fd_A"] == pytest.approx(2.22e-16, rel=2e-3, abs=0)


def tutorial_blocks():
    blocks = sh_blocks((ROOT / "docs" / "tutorial.md").read_text())
    assert len(blocks) >= 8, "the tutorial lost its commands"
    return blocks


@pytest.mark.slow
def test_tutorial_runs_as_written(clone):
    run_blocks(tutorial_blocks(), clone, page=ROOT / "docs" / "tutorial.md")


def test_tutorial_quick_blocks_run_and_slow_commands_parse(clone):
    blocks = tutorial_blocks()
    assert any(b["slow"] for b in blocks) and not all(b["slow"] for b in blocks)
    run_blocks(blocks, clone, parse_slow=True, page=ROOT / "docs" / "tutorial.md")


def test_readme_tour_runs_as_written(clone):
    """The README's blocks after its two set-up commands (the tour; the set-up itself is tests/test_setup.py's)."""
    blocks = sh_blocks((ROOT / "README.md").read_text())[2:]
    assert blocks, "the README lost its tour"
    run_blocks(blocks, clone, page=ROOT / "README.md")


def test_the_runner_catches_a_stale_command(clone):
    """The check can fail: a command whose option no longer exists, and a block that does not
    leave the file the page promises."""
    with pytest.raises(AssertionError, match="exited 2"):
        run_blocks(sh_blocks("```sh\npixelkit simulate designs/dual_pixel_revA.toml --no-such-option\n```"), clone)
    with pytest.raises(AssertionError, match="did not create"):
        run_blocks(sh_blocks("<!-- creates: out/x.csv -->\n```sh\ntrue\n```"), clone)
    assert sh_blocks("<!-- exit: 0 1 -->\n```sh\nfalse\n```")[0]["exit"] == {0, 1}
    slow = "<!-- slow -->\n```sh\npixelkit report designs/dual_pixel_revA.toml --quick --out r \\\n  --bogus 1\n```"
    with pytest.raises(AssertionError, match="No such option '--bogus'"):
        run_blocks(sh_blocks(slow), clone, parse_slow=True)
    with pytest.raises(AssertionError, match="does not exist"):
        run_blocks(sh_blocks(slow.replace("designs/dual_pixel_revA", "revZ").replace("--bogus 1", "")), clone,
                   parse_slow=True)
    with pytest.raises(AssertionError, match="did not print"):
        run_blocks(sh_blocks("<!-- expect: fd_leakage -->\n```sh\necho dark_current\n```"), clone)
    with pytest.raises(AssertionError, match="No such command"):
        run_blocks(sh_blocks("<!-- slow -->\n```sh\npixelkit reprot x\n```"), clone, parse_slow=True)


def test_the_runner_holds_a_pages_output_against_the_printed_one(clone, monkeypatch):
    """A text block after a command is what it prints: a number that moved beyond the digits
    quoted fails naming it, a line no longer printed fails, a ``vary`` line's numbers and the
    cut lines pass; with PIXELKIT_DOCS_REWRITE=1 the page is rewritten from the output."""
    printed = "printf 'CG (uV/e-)   4.036   11.41\\nread noise 408.9 e-\\n16 SPICE runs (0 from cache) in 13.4 s\\n'"
    page = "```sh\n" + printed + "\n```\n\n<!-- vary: read noise -->\n```text\n{}\n```\n"
    ok = "CG (uV/e-) 4.04 11.41\n...\nread noise 401.0 e-\n16 SPICE runs (16 from cache) in 2.0 s"
    run_blocks(sh_blocks(page.format(ok)), clone)
    with pytest.raises(AssertionError, match=r"4\.112 -> 4\.036"):
        run_blocks(sh_blocks(page.format("CG (uV/e-)   4.112   11.41")), clone)
    with pytest.raises(AssertionError, match="not printed"):
        run_blocks(sh_blocks(page.format("CG_out(0) (uV/e-)   4.036   11.41")), clone)
    doc = clone / "page.md"
    doc.write_text("intro\n" + page.format("CG (uV/e-)   4.112   11.41\nread noise 1 e-") + "outro\n")
    monkeypatch.setenv("PIXELKIT_DOCS_REWRITE", "1")
    run_blocks(sh_blocks(doc.read_text()), clone, page=doc)
    assert doc.read_text() == "intro\n" + page.format("CG (uV/e-)   4.036   11.41\nread noise 1 e-") + "outro\n"



def test_other_pages_blocks_marked_run_run_as_written(clone):
    """A reference page's block marked ``<!-- run -->`` (a quick command whose output the page shows and
    reads: docs/emva1288.md) is run like the tutorial's, its output held against the page's."""
    ran = {"tutorial.md", *HOWTOS}
    n = 0
    for page in sorted((ROOT / "docs").glob("*.md")):
        blocks = [b for b in sh_blocks(page.read_text()) if b["run"]] if page.name not in ran else []
        n += len(blocks)
        try:
            run_blocks(blocks, clone, page=page)
        except AssertionError as e:
            raise AssertionError(f"docs/{page.name}: {e}") from None
    assert n >= 1, "no block marked run: the marker parser lost them"


def test_every_other_pages_commands_parse():
    """The ```sh blocks of every other docs page (physics, references, internals) are not run, but
    their ``pixelkit`` commands parse with the real click commands from the repository's root:
    a renamed command or option or a design file that is not there fails (the parser is shown to
    fail in test_the_runner_catches_a_stale_command)."""
    ran = {"tutorial.md", *HOWTOS}
    n = 0
    for page in sorted((ROOT / "docs").glob("*.md")):
        if page.name in ran:
            continue
        blocks = [{**b, "parse_only": True, "creates": []} for b in sh_blocks(page.read_text())]
        n += sum(len(pixelkit_commands(b["code"])) for b in blocks)
        try:
            run_blocks(blocks, ROOT)
        except AssertionError as e:
            raise AssertionError(f"docs/{page.name}: {e}") from None
    assert n >= 3, f"only {n} commands found on the other pages: the block parser lost them"


SPAN = re.compile(r"`(?:python3? -m |\.venv/bin/python -m )?pixelkit ([^`]+)`")


def stale_mentions(text: str) -> list[str]:
    """Inline ``pixelkit CMD [SUB] [--option ...]`` spans outside fenced blocks whose command,
    subcommand or option does not exist (``COMMAND`` or ``...`` is a placeholder)."""
    from pixelkit.cli import register_all
    from pixelkit.cli.common import main
    register_all()
    bad = []
    for m in SPAN.finditer(re.sub(r"```.*?```", "", text, flags=re.S)):
        words = m.group(1).split()
        if not re.fullmatch(r"[a-z][a-z0-9_-]*", words[0]):     # a placeholder: COMMAND, ...
            continue
        cmd = main.commands.get(words[0])
        if cmd is None:
            bad.append(f"{m.group(0)}: no command {words[0]!r}")
            continue
        rest = words[1:]
        if isinstance(cmd, click.Group):
            if not rest or rest[0].startswith("-") or rest[0].isupper():
                continue
            if rest[0] not in cmd.commands:
                bad.append(f"{m.group(0)}: no command {words[0]} {rest[0]!r}")
                continue
            cmd, rest = cmd.commands[rest[0]], rest[1:]
        known = {o for p in cmd.params for o in (*getattr(p, "opts", ()), *getattr(p, "secondary_opts", ()))}
        bad += [f"{m.group(0)}: no option {o}" for w in rest if (o := re.match(r"--?[A-Za-z][\w-]*", w.lstrip("[(")))
                and (o := o.group(0)) not in known | {"--help", "-h"}]
    return bad


def test_every_command_mentioned_in_the_docs_and_readme_exists():
    """Every inline `pixelkit ...` mention on the docs pages and in the README names a command,
    subcommand and options the kit has (about a hundred mentions); a planted stale one is found."""
    pages = [ROOT / "README.md", *sorted((ROOT / "docs").glob("*.md"))]
    bad = [f"{p.name}: {b}" for p in pages for b in stale_mentions(p.read_text())]
    assert not bad, "\n".join(bad)
    assert stale_mentions("`pixelkit reprot D`, `pixelkit gap diagnoze`, `pixelkit layout D --drcc`, "
                          "`pixelkit size D [--outt F]`, `pixelkit COMMAND --help`, `pixelkit gap DATASET`, "
                          "`pixelkit ...`") == [
        "`pixelkit reprot D`: no command 'reprot'", "`pixelkit gap diagnoze`: no command gap 'diagnoze'",
        "`pixelkit layout D --drcc`: no option --drcc", "`pixelkit size D [--outt F]`: no option --outt"]


def test_the_runner_starts_a_pages_server_on_a_port_of_its_own_and_ends_it(clone, capfd):
    """A ``<!-- background: HOST:PORT -->`` block (the Dask how-to's scheduler and workers) runs in the
    background on a free port that replaces the page's in the later blocks, and is ended after the walk."""
    import socket
    page = ("<!-- background: 127.0.0.1:8786 -->\n```sh\npython -m http.server --bind 127.0.0.1 8786 &\n```\n\n"
            "```sh\npython -c 'import urllib.request as u; print(u.urlopen(\"http://127.0.0.1:8786/\").status)' "
            "&& echo 127.0.0.1:8786 > port.txt\n```\n\n```text\n200\n```\n")
    run_blocks(sh_blocks(page), clone)
    port = int((clone / "port.txt").read_text().strip().rsplit(":", 1)[1])
    assert port != 8786
    with socket.socket() as s:
        assert s.connect_ex(("127.0.0.1", port)) != 0, "the page's server is still running"
