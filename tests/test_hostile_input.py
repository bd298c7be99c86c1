"""Hostile input through the real command line: bounded, refused with file:line, no traceback.

Each test writes its hostile files in ``tmp_path`` and runs ``bt_manip.cli.main`` in a child
process limited to 1.5 GB of address space (a regression then fails the test instead of eating
the machine) and bounded by a subprocess time-out. Several invocations share one child, which
records for each its exit code, stdout, stderr, the CPU time it took (less than 5 s each: CPU
time, not wall time, so that a busy machine does not fail the test) and the child's peak
memory so far (less than 1 GB).
"""

from __future__ import annotations

import itertools
import json
import os
import re
import resource
import subprocess
import sys
import textwrap
from pathlib import Path
from typing import Any

ROOT = Path(__file__).resolve().parents[1]
ADDRESS_SPACE = 1536 * 1024 * 1024
PER_CHECK_SECONDS = 5.0
PEAK_MB = 1024

DRIVER = textwrap.dedent(
    """
    import contextlib, io, json, resource, sys, traceback
    from bt_manip.cli import main

    def cpu():
        usage = resource.getrusage(resource.RUSAGE_SELF)
        return usage.ru_utime + usage.ru_stime

    def peak_mb():
        # this program's own high-water mark (VmHWM starts afresh at exec; ru_maxrss keeps the
        # peak of the test process this child was forked from)
        for line in open("/proc/self/status"):
            if line.startswith("VmHWM:"):
                return int(line.split()[1]) / 1024
        return resource.getrusage(resource.RUSAGE_SELF).ru_maxrss / 1024

    results = []
    for argv in json.load(open(sys.argv[1])):
        out, err = io.StringIO(), io.StringIO()
        start = cpu()
        with contextlib.redirect_stdout(out), contextlib.redirect_stderr(err):
            try:
                code = main(argv)
            except SystemExit as exc:
                code = exc.code if isinstance(exc.code, int) else 2
            except BaseException:
                code = None
                traceback.print_exc()
        results.append({
            "code": code, "out": out.getvalue(), "err": err.getvalue(),
            "cpu_seconds": cpu() - start,
            "peak_mb": peak_mb(),
        })
    json.dump(results, open(sys.argv[2], "w"))
    """
)


def _limit_memory() -> None:
    resource.setrlimit(resource.RLIMIT_AS, (ADDRESS_SPACE, ADDRESS_SPACE))


def _env() -> dict[str, str]:
    return {**os.environ, "PYTHONPATH": str(ROOT)}


def run_cli(tmp_path: Path, *invocations: list[str]) -> list[dict[str, Any]]:
    """Run each argv through ``bt_manip.cli.main`` in one bounded child; their results."""
    checks, results = tmp_path / "checks.json", tmp_path / "results.json"
    checks.write_text(json.dumps([[str(a) for a in argv] for argv in invocations]))
    done = subprocess.run(
        [sys.executable, "-c", DRIVER, str(checks), str(results)],
        preexec_fn=_limit_memory,
        capture_output=True,
        text=True,
        timeout=60 + 2 * PER_CHECK_SECONDS * len(invocations),
        env=_env(),
        cwd=tmp_path,
    )
    assert done.returncode == 0, done.stderr[-3000:]
    assert "Traceback" not in done.stdout + done.stderr
    out = json.loads(results.read_text())
    for argv, result in zip(invocations, out, strict=True):
        text = result["out"] + result["err"]
        assert "Traceback" not in text, (argv, text[-3000:])
        assert result["cpu_seconds"] < PER_CHECK_SECONDS, (argv, result["cpu_seconds"])
        assert result["peak_mb"] < PEAK_MB, (argv, result["peak_mb"])
    return out


def _tree(path: Path, body: str, extra: str = "") -> Path:
    path.write_text(
        '<root BTCPP_format="4" main_tree_to_execute="Main">\n'
        f'  <BehaviorTree ID="Main">\n{body}\n  </BehaviorTree>\n{extra}</root>\n'
    )
    return path


def _chain(path: Path, levels: int, leaf: str = "<AlwaysSuccess/>") -> Path:
    """Main -> T1 -> ... -> T<levels>: each tree a Sequence holding the SubTree of the next."""
    names = ["Main"] + [f"T{i}" for i in range(1, levels + 1)]
    lines = ['<root BTCPP_format="4" main_tree_to_execute="Main">']
    for here, below in itertools.pairwise(names):
        lines.append(f'<BehaviorTree ID="{here}"><Sequence><SubTree ID="{below}"/></Sequence>'
                     "</BehaviorTree>")
    lines.append(f'<BehaviorTree ID="{names[-1]}">{leaf}</BehaviorTree>')
    lines.append("</root>")
    path.write_text("\n".join(lines) + "\n")
    return path


def _deep_halt(path: Path, levels: int = 255, inner: int = 7) -> Path:
    """A Timeout over ``levels`` SubTrees, each ``inner`` controls deep, above a long Sleep: the
    Timeout halts a RUNNING branch about ``levels * (inner + 1)`` nodes deep."""
    lines = ['<root BTCPP_format="4" main_tree_to_execute="Main">',
             '<BehaviorTree ID="Main"><Timeout msec="50"><SubTree ID="T0"/></Timeout>'
             "</BehaviorTree>"]
    for i in range(levels):
        body = f'<SubTree ID="T{i + 1}"/>'
        for j in range(inner):
            body = (f"<Sequence>{body}</Sequence>" if j % 2 == 0
                    else f"<ReactiveSequence><AlwaysSuccess/>{body}</ReactiveSequence>")
        lines.append(f'<BehaviorTree ID="T{i}">{body}</BehaviorTree>')
    lines.append(f'<BehaviorTree ID="T{levels}"><Sleep msec="100000"/></BehaviorTree></root>')
    path.write_text("\n".join(lines) + "\n")
    return path


def test_trees_deep_chains_bad_literals_and_flags(tmp_path: Path) -> None:
    chain256 = _chain(tmp_path / "chain256.xml", 256, '<Script code="@done := @depth + 1"/>')
    chain400 = _chain(tmp_path / "chain400.xml", 400)
    chain2000 = _chain(tmp_path / "chain2000.xml", 2000)
    literals = _tree(tmp_path / "literals.xml", "\n".join([
        "    <Sequence>",
        '      <Timeout msec="-100"><AlwaysSuccess/></Timeout>',  # line 4
        '      <CloseGripper timeout="-5"/>',
        '      <Lift height="nan"/>',
        '      <Lift height="inf"/>',
        '      <MoveJoints targets="0;1;-inf" units="grad" speed="2"/>',
        '      <OpenGripper opening="-0.5"/>',
        '      <OpenGripper opening="-1"/>',  # fine: -1 means fully
        '      <Sleep msec="-3"/>',
        '      <Navigate goal="1;2"/>',
        '      <Navigate goal="nan;0;0"/>',
        '      <Navigate goal="kitchen"/>',  # fine: a pose name is looked up at run time
        '      <MoveToPose position="1;2" orientation="0;0;1"/>',
        '      <Delay delay_msec="-5"><AlwaysSuccess/></Delay>',
        "    </Sequence>",
    ]))
    runtime = _tree(tmp_path / "runtime.xml", "\n".join([
        "    <Sequence>",
        '      <Script code="y := x + 1"/>',
        '      <Timeout msec="{m}"><AlwaysSuccess/></Timeout>',  # line 5
        "    </Sequence>",
    ]))
    models = tmp_path / "models.xml"
    models.write_text(
        '<root BTCPP_format="4"><TreeNodesModel>\n'
        '  <Action ID="Grab">\n'
        '    <input_port name="count" type="int"/>\n'
        '    <input_port name="force" type="double"/>\n'
        '    <input_port name="wait" type="unsigned int"/>\n'
        '    <output_port name="result" type="std::string"/>\n'
        "  </Action>\n"
        "</TreeNodesModel></root>\n"
    )
    uses_model = _tree(tmp_path / "uses_model.xml", "\n".join([
        "    <Sequence>",
        '      <Grab count="three" force="nan" wait="-1" result="text"/>',  # line 4
        '      <Grab count="{c}" force="2.5" wait="10" result="{r}"/>',
        "    </Sequence>",
    ]))
    huge = tmp_path / "huge.xml"
    huge.write_bytes(b"<root>" + b" " * (10 * 1024 * 1024) + b"</root>")
    includes = tmp_path / "includes"
    includes.mkdir()
    for i in range(300):  # i.xml includes i+1.xml, 300 levels deep
        _include_file(includes / f"{i}.xml", f"{i + 1}.xml")
    _tree(includes / "300.xml", "    <AlwaysSuccess/>")
    diamond = tmp_path / "diamond"
    diamond.mkdir()
    for i in range(40):  # 2 ** 40 reads if a file included twice were read twice
        _include_file(diamond / f"f{i}.xml", f"a{i}.xml", f"b{i}.xml")
        _include_file(diamond / f"a{i}.xml", f"f{i + 1}.xml")
        _include_file(diamond / f"b{i}.xml", f"f{i + 1}.xml")
    _tree(diamond / "f40.xml", "    <AlwaysSuccess/>")
    scripts = _tree(tmp_path / "scripts.xml", "\n".join([
        "    <Sequence>",
        '      <Script code="x := ' + "(" * 5000 + "1" + ")" * 5000 + '"/>',  # line 4
        '      <Script code="x := ' + "-" * 5000 + '1"/>',
        '      <Script code="x := 1' + " + 1" * 4000 + '"/>',  # under the length limit
        '      <AlwaysSuccess _skipIf="' + "!" * 200 + 'true"/>',
        '      <Script code="x := ' + "(" * 20 + "1" + " + 1" * 90 + ")" * 20 + '"/>',  # fine
        "    </Sequence>",
    ]))
    bb_out = tmp_path / "bb.json"
    fifo = tmp_path / "fifo.xml"
    os.mkfifo(fifo)

    results = run_cli(
        tmp_path,
        ["run", "/dev/zero"],
        ["validate", fifo],
        ["validate", huge],
        ["run", chain400, "--quiet"],
        ["validate", chain2000],
        ["validate", chain256],
        ["run", chain256, "--quiet", "--bb", "depth=256", "--bb-out", bb_out],
        ["run", _deep_halt(tmp_path / "deep_halt.xml"), "--quiet"],
        ["validate", literals],
        ["run", literals, "--quiet"],
        ["run", runtime, "--quiet", "--bb", "x=1", "--bb", "m=-100"],
        ["run", runtime, "--quiet", "--bb", "x=1", "--bb", "m=5", "--inject",
         "Timeot:failure:0.5"],
        ["run", runtime, "--quiet", "--inject", "NoSuchNode:failure:0.5"],
        ["run", runtime, "--quiet", "--inject", "Script:failur:0.5"],
        ["run", runtime, "--quiet", "--inject", "slp:0.5"],
        ["validate", uses_model, "--models", models],
        ["validate", includes / "0.xml"],
        ["run", diamond / "f0.xml", "--quiet"],
        ["validate", scripts],
        ["run", runtime, "--tick-hz", "1e-300"],
        ["run", runtime, "--realtime", "nan"],
        ["world", "nowhere.yaml", "--settle", "inf"],
        ["bench", runtime, "--world", "w.yaml", "--jobs", "100000"],
    )
    (dev_zero, fifo_r, huge_r, run400, val2000, val256, run256, deep_halt, val_lit, run_lit,
     bad_bb, typo, no_node, bad_kind, bad_world_kind, model_types, deep_includes, twice,
     deep_scripts, *flags) = results

    assert dev_zero["code"] == 2
    assert dev_zero["err"] == "/dev/zero: file is a device, not a regular file\n"
    assert fifo_r["code"] == 2
    assert fifo_r["err"] == f"{fifo}: file is a pipe, not a regular file\n"
    assert huge_r["code"] == 2
    assert huge_r["err"] == f"{huge}: file is larger than the limit of 10 MB\n"

    deep = "allows at most 256 levels of SubTree nesting"
    assert run400["code"] == 2
    assert run400["err"].startswith(f"{chain400}:2: SubTrees nested 400 levels deep (Main -> T1")
    assert deep in run400["err"]
    assert val2000["code"] == 2
    assert val2000["err"].startswith(f"{chain2000}:2: SubTrees nested 2000 levels deep")
    assert val256["code"] == 0 and val256["out"] == f"{chain256}: OK\n"
    assert run256["code"] == 0 and "result: SUCCESS" in run256["out"]
    assert json.loads(bb_out.read_text())["done"] == 257
    assert deep_halt["code"] == 1
    assert "result: FAILURE (Timeout: timed out after 50 ms)" in deep_halt["out"]

    expected = [
        f"{literals}:4: bad value for port 'msec' of Timeout: must be >= 0, got -100",
        f"{literals}:5: bad value for port 'timeout' of CloseGripper: must be > 0, got -5",
        f"{literals}:6: bad value for port 'height' of Lift: expected a finite number, got 'nan'",
        f"{literals}:7: bad value for port 'height' of Lift: expected a finite number, got 'inf'",
        f"{literals}:8: bad value for port 'speed' of MoveJoints: must be in (0, 1], got 2",
        f"{literals}:8: bad value for port 'targets' of MoveJoints: expected a finite number, "
        "got '-inf'",
        f"{literals}:8: bad value for port 'units' of MoveJoints: must be one of deg, rad, "
        "got grad",
        f"{literals}:9: bad value for port 'opening' of OpenGripper: must be >= 0 or -1, "
        "got -0.5",
        f"{literals}:11: bad value for port 'msec' of Sleep: must be >= 0, got -3",
        f"{literals}:12: bad value for port 'goal' of Navigate: a goal written as numbers must "
        "be three finite numbers x;y;yaw, got '1;2'",
        f"{literals}:13: bad value for port 'goal' of Navigate: a goal written as numbers must "
        "be three finite numbers x;y;yaw, got 'nan;0;0'",
        f"{literals}:15: bad value for port 'position' of MoveToPose: must hold 0 or 3 values, "
        "got 2",
        f"{literals}:15: bad value for port 'orientation' of MoveToPose: must hold 4 values, "
        "got 3",
        f"{literals}:16: bad value for port 'delay_msec' of Delay: must be >= 0, got -5",
    ]
    for result in (val_lit, run_lit):
        assert result["code"] == 2
        assert sorted(result["err"].splitlines()) == sorted(expected)

    assert bad_bb["code"] == 1
    assert ("result: FAILURE (Sequence/Timeout: Timeout (line 5): input port 'msec' (entry "
            "'m'): must be >= 0, got -100)") in bad_bb["out"]

    assert typo["code"] == 2
    assert typo["err"] == ("--inject: 'Timeot:failure:0.5': no node of the tree is named "
                           "'Timeot' or has that node ID (did you mean 'Timeout'?)\n")
    assert no_node["code"] == 2
    assert no_node["err"].startswith("--inject: 'NoSuchNode:failure:0.5': no node of the tree")
    assert "AlwaysSuccess, Script, Sequence, Timeout" in no_node["err"]
    assert bad_kind["code"] == 2
    assert "--inject: 'Script:failur:0.5': unknown fault kind 'failur' (did you mean " \
           "'failure'?)" in bad_kind["err"]
    assert bad_world_kind["code"] == 2
    assert "unknown fault kind 'slp' (did you mean 'slip'?)" in bad_world_kind["err"]

    assert model_types["code"] == 2
    assert model_types["err"].splitlines() == [
        f"{uses_model}:4: bad value for port 'count' of Grab: expected an integer, got 'three' "
        '(its TreeNodesModel declares type="int")',
        f"{uses_model}:4: bad value for port 'force' of Grab: expected a finite number, got "
        "'nan' (its TreeNodesModel declares type=\"double\")",
        f"{uses_model}:4: bad value for port 'wait' of Grab: expected a non-negative integer, "
        "got '-1' (its TreeNodesModel declares type=\"unsigned int\")",
        f"{uses_model}:4: bad value for port 'result' of Grab: an output port takes a blackboard "
        "reference like \"{result}\", got 'text'",
    ]

    assert deep_includes["code"] == 2
    assert deep_includes["err"] == (f"{includes / '256.xml'}:1: includes nested deeper than 256 "
                                    "levels; bt-manip reads at most that many\n")
    assert twice["code"] == 2
    assert len(twice["err"].splitlines()) == 40
    assert twice["err"].startswith(
        f"{diamond / 'b0.xml'}:1: 'f1.xml' is already included (at {diamond / 'a0.xml'}:1); "
        "include each file once, its trees would be defined twice\n")

    assert [(f["code"], f["err"]) for f in flags] == [
        (2, "bt-manip run: argument --tick-hz: must be within 0.1..1000, got 1e-300 "
            "(see bt-manip run --help)\n"),
        (2, "bt-manip run: argument --realtime: must be within 0.01..1000, got nan "
            "(see bt-manip run --help)\n"),
        (2, "bt-manip world: argument --settle: must be within 0..3600, got inf "
            "(see bt-manip world --help)\n"),
        (2, "bt-manip bench: argument --jobs: must be within 1..64, got 100000 "
            "(see bt-manip bench --help)\n"),
    ]
    unparsable = ("expression nested too deeply to parse (parentheses or operators); split it "
                  "into several statements (column 1 of the script)")
    too_deep = ("expression nested deeper than 100 levels; split it into several statements "
                "(column 1 of the script)")
    assert deep_scripts["code"] == 2
    assert deep_scripts["err"].splitlines() == [
        f"{scripts}:4: script syntax error in code of Script: {unparsable}",
        f"{scripts}:5: script syntax error in code of Script: {unparsable}",
        f"{scripts}:6: script syntax error in code of Script: {too_deep}",
        f"{scripts}:7: script syntax error in _skipIf of AlwaysSuccess: {too_deep}",
    ]


def _include_file(path: Path, *targets: str) -> None:
    path.write_text('<root BTCPP_format="4">'
                    + "".join(f'<include path="{t}"/>' for t in targets) + "</root>\n")


def _alias_bomb(path: Path, depth: int = 9, width: int = 9) -> Path:
    """A world whose poses nest aliases ``depth`` deep, each level ``width`` copies wide."""
    lines = ["name: bomb", "poses:", "  a0: &a0 [0, 0, 0]"]
    for i in range(1, depth + 1):
        lines.append(f"  a{i}: &a{i} [{', '.join([f'*a{i - 1}'] * width)}]")
    path.write_text("\n".join(lines) + "\n")
    return path


BAD_MESH_URDF = """<robot name="statue">
  <link name="base">
    <visual><geometry><mesh filename="{mesh}"/></geometry></visual>
    <inertial><mass value="1"/>
      <inertia ixx="0.1" iyy="0.1" izz="0.1" ixy="0" ixz="0" iyz="0"/></inertial>
  </link>
</robot>
"""


def _furniture_world(folder: Path, name: str, mesh: str) -> Path:
    (folder / f"{name}.urdf").write_text(BAD_MESH_URDF.format(mesh=mesh))
    world = folder / f"{name}.yaml"
    world.write_text(f"name: {name}\nfurniture:\n  - name: statue\n    urdf: {name}.urdf\n"
                     "    pose: [1, 0, 0]\n")
    return world


def _doubling(path: Path, levels: int) -> Path:
    """T0 -> T1 -> ... -> T<levels>: each tree a Sequence of two SubTrees of the next, so T0
    holds 2 ** (levels + 2) - 3 nodes once expanded."""
    trees = [f'<BehaviorTree ID="T{i}"><Sequence><SubTree ID="T{i + 1}"/>'
             f'<SubTree ID="T{i + 1}"/></Sequence></BehaviorTree>' for i in range(levels)]
    path.write_text('<root BTCPP_format="4" main_tree_to_execute="T0">\n' + "\n".join(trees)
                    + f'\n<BehaviorTree ID="T{levels}"><AlwaysSuccess/></BehaviorTree>\n</root>\n')
    return path


def _scripts(path: Path, codes: list[str]) -> Path:
    """Main: a Sequence of one Script per code, each on its own line (the first on line 4)."""
    return _tree(path, "    <Sequence>\n" + "\n".join(
        f'      <Script code="{code}"/>' for code in codes) + "\n    </Sequence>")


def test_subtrees_that_multiply_and_scripts_that_add_up_are_refused_before_building(
        tmp_path: Path) -> None:
    big = "x:=x+1;" * 2800  # 19,600 characters, under the limit of one script
    results = run_cli(
        tmp_path,
        ["validate", _doubling(tmp_path / "d60.xml", 60)],
        ["run", _doubling(tmp_path / "d14.xml", 14), "--quiet"],
        ["run", _doubling(tmp_path / "d3.xml", 3), "--quiet"],
        ["validate", _scripts(tmp_path / "long.xml", ["x:=1;" * 1_000_000])],
        ["validate", _scripts(tmp_path / "many.xml", [f"y{i}:=0;{big}" for i in range(30)])],
        ["run", _scripts(tmp_path / "same.xml", ["x:=0;"] + [big] * 100), "--quiet",
         "--bb-out", tmp_path / "bb.json"],
    )
    d60, d14, d3, long, many, same = results
    assert d60["code"] == 2
    assert d60["err"] == (f"{tmp_path / 'd60.xml'}:2: tree 'T0' holds about 4.6e+18 nodes once "
                          "its SubTrees are expanded; bt-manip builds at most 50,000\n")
    assert d14["code"] == 2
    assert d14["err"] == (f"{tmp_path / 'd14.xml'}:2: tree 'T0' holds 65,533 nodes once its "
                          "SubTrees are expanded; bt-manip builds at most 50,000\n")
    assert d3["code"] == 0 and "result: SUCCESS" in d3["out"]
    assert long["code"] == 2
    assert long["err"] == (
        f"{tmp_path / 'long.xml'}:4: script syntax error in code of Script: script of "
        "5,000,000 characters, more than the limit of 20,000; split it into several scripts "
        "(column 1 of the script)\n")
    # 12 scripts of 19,6xx characters fit in 250,000, the 13th (line 4 + 12) does not
    assert many["code"] == 2
    assert many["err"] == (f"{tmp_path / 'many.xml'}:16: the scripts of this file pass 250,000 "
                           "characters at code of Script; bt-manip reads at most that many\n")
    # the same text a hundred times counts once, and is parsed once
    assert same["code"] == 0 and "result: SUCCESS" in same["out"]
    assert json.loads((tmp_path / "bb.json").read_text())["x"] == 280_000


def _chain_urdf(path: Path, links: int, one_line: bool = False) -> Path:
    """A robot of ``links`` boxes in a chain of revolute joints (links on lines 2.. unless
    ``one_line``)."""
    box = '<geometry><box size="0.1 0.1 0.1"/></geometry>'
    parts = [f'<link name="l{i}"><inertial><mass value="1"/><inertia ixx="0.1" iyy="0.1" '
             f'izz="0.1" ixy="0" ixz="0" iyz="0"/></inertial><collision>{box}</collision>'
             "</link>" for i in range(links)]
    parts += [f'<joint name="j{i}" type="revolute"><parent link="l{i}"/><child link="l{i + 1}"/>'
              '<axis xyz="0 0 1"/><limit lower="-1" upper="1" effort="1" velocity="1"/></joint>'
              for i in range(links - 1)]
    sep = "" if one_line else "\n"
    path.write_text(f'<robot name="chain">{sep}' + sep.join(parts) + f"{sep}</robot>\n")
    return path


def test_urdfs_of_too_many_links_are_refused_before_a_library_reads_them(tmp_path: Path) -> None:
    huge = _chain_urdf(tmp_path / "huge.urdf", 20_000)  # 7 MB: under the byte limit
    assert huge.stat().st_size < 8 * 1024 * 1024
    one_line = _chain_urdf(tmp_path / "one_line.urdf", 20_000, one_line=True)
    wide = _chain_urdf(tmp_path / "wide.urdf", 200)
    fits = _chain_urdf(tmp_path / "fits.urdf", 20)
    world = tmp_path / "statue.yaml"
    world.write_text("name: statue\nfurniture:\n  - name: statue\n    urdf: huge.urdf\n"
                     "    pose: [1, 0, 0]\n  - name: wide\n    urdf: wide.urdf\n"
                     "    pose: [3, 0, 0]\n")
    loaded = tmp_path / "wide_only.yaml"
    loaded.write_text("name: wide\nfurniture:\n  - name: wide\n    urdf: wide.urdf\n"
                      "    pose: [3, 0, 0]\n")

    def init(urdf: Path) -> list[str]:
        return ["robot", "init", str(urdf), "--base-link", "l0", "--arm-tip", "l7",
                "--out", str(tmp_path / f"{urdf.stem}.yaml")]

    big, flat, many, ok, furniture, wide_world = run_cli(
        tmp_path, init(huge), init(one_line), init(wide), init(fits),
        ["world", str(world)], ["world", str(loaded)])
    limit = "the URDF has 20,000 <link> elements, more than the limit of 1,000"
    assert (big["code"], big["err"]) == (2, f"{huge}:1002: {limit}\n")
    assert (flat["code"], flat["err"]) == (2, f"{one_line}:1: {limit}\n")
    pybullet = "PyBullet answers for at most 128 links of one body, and this URDF loads as 200"
    assert many["code"] == 2 and many["err"].endswith(f"{wide}: {pybullet}\n")
    assert ok["code"] == 0 and "arm 7 joints (l0 -> l7)" in ok["out"]
    assert furniture["code"] == 2
    assert f"{world}:4: furniture[0].urdf: {limit} (huge.urdf:1002)" in furniture["err"]
    assert wide_world["code"] == 2
    assert wide_world["err"].endswith(f"{loaded}:3: 'wide': {pybullet} ({wide})\n")


def test_worlds_alias_bombs_sizes_devices_and_meshes(tmp_path: Path) -> None:
    bomb = _alias_bomb(tmp_path / "bomb.yaml")
    assert bomb.stat().st_size < 600
    many = tmp_path / "many.yaml"  # 9,000 boxes of 11 values each, 0.75 MB
    many.write_text("name: many\nfurniture:\n" + "".join(
        f"  - {{name: b{i}, pose: [{i % 100}, {i // 100}, 0], parts: [{{shape: box, "
        "size: [0.1, 0.1, 0.1]}]}\n" for i in range(9000)))
    big = tmp_path / "big.yaml"
    big.write_text("name: big\n" + "# padding\n" * 110_000)
    (tmp_path / "statue.png").write_bytes(b"\x89PNG not a mesh")
    (tmp_path / "statue.stl").write_text("this is not a mesh\n")
    png = _furniture_world(tmp_path, "png_mesh", "statue.png")
    garbage = _furniture_world(tmp_path, "garbage_mesh", "statue.stl")

    fast = tmp_path / "fast.yaml"
    fast.write_text("name: fast\nphysics: {rate_hz: 1000000000000, solver_iterations: 10000}\n"
                    "poses:\n  p: [" + ", ".join(["1"] * 50_000) + "]\n")
    results = run_cli(
        tmp_path,
        ["world", fast],
        ["world", bomb],
        ["world", many],
        ["world", big],
        ["world", "/dev/zero"],
        ["world", tmp_path],
        ["world", png],
        ["world", garbage],
    )
    r_fast, r_bomb, r_many, r_big, r_zero, r_dir, r_png, r_garbage = results
    assert r_fast["code"] == 2
    fast_lines = r_fast["err"].splitlines()
    assert fast_lines[:2] == [
        f"{fast}:2: physics.rate_hz must be within 10..10000, got 1000000000000",
        f"{fast}:2: physics.solver_iterations must be within 1..1000, got 10000",
    ]
    assert fast_lines[2].startswith(f"{fast}:4: poses.p ([x, y, yaw]) must be a list of 3 numbers")
    assert fast_lines[2].endswith(" ... (cut short)") and len(fast_lines[2]) < 1200
    assert r_bomb["code"] == 2
    assert r_bomb["err"].startswith(f"{bomb}:")
    too_many = ("refused YAML: more than 100000 values (the limit of a YAML input; each use of "
                "an alias counts as a copy of what it names)\n")
    assert r_bomb["err"] == f"{bomb}:8: {too_many}"  # the expanded value is not printed
    assert r_many["code"] == 2
    assert r_many["err"] == f"{many}:3: {too_many}"
    assert r_big["code"] == 2
    assert r_big["err"] == f"{big}: YAML file is larger than the limit of 1 MB\n"
    assert r_zero["code"] == 2
    assert r_zero["err"] == "/dev/zero: YAML file is a device, not a regular file\n"
    assert r_dir["code"] == 2
    assert r_dir["err"] == f"{tmp_path}: YAML file is a directory, not a regular file\n"
    assert r_png["code"] == 2
    assert r_png["err"] == (
        f"{png}:4: furniture[0].urdf: mesh 'statue.png' is not a mesh PyBullet reads; use an "
        ".stl, .obj or .dae file (named in png_mesh.urdf:3)\n")
    assert r_garbage["code"] == 2
    assert r_garbage["err"] == (
        f"{garbage}:4: furniture[0].urdf: mesh 'statue.stl' is not an STL mesh (no triangles "
        "found in statue.stl) (named in garbage_mesh.urdf:3)\n")


def test_robot_nodes_fail_with_the_reason_on_bad_blackboard_values(tmp_path: Path) -> None:
    tree = _tree(tmp_path / "grip.xml", '    <CloseGripper timeout="{t}"/>')
    table = ROOT / "worlds" / "sawyer_table.yaml"
    negative, text = run_cli(
        tmp_path,
        ["run", tree, "--world", table, "--quiet", "--bb", "t=-5"],
        ["run", tree, "--world", table, "--quiet", "--bb", "t=nan"],
    )
    assert negative["code"] == 1
    assert ("result: FAILURE (CloseGripper: CloseGripper (line 3): input port 'timeout' "
            "(entry 't'): must be > 0, got -5)") in negative["out"]
    assert text["code"] == 1
    assert ("result: FAILURE (CloseGripper: CloseGripper (line 3): input port 'timeout' "
            "(entry 't'): expected a finite number, got 'nan')") in text["out"]


def test_navigate_in_a_world_too_large_for_its_grid_fails_with_the_extent(tmp_path: Path) -> None:
    world = tmp_path / "square.yaml"
    world.write_text(
        "name: square\nwalls:\n"
        "  - {name: north, from: [-2000, 2000], to: [2000, 2000], thickness: 0.15, height: 1.5}\n"
        "  - {name: south, from: [-2000, -2000], to: [2000, -2000], thickness: 0.15, "
        "height: 1.5}\n"
        "robots:\n  - {name: husky, description: husky_ur3, pose: [0, 0, 0]}\n"
    )
    tree = _tree(tmp_path / "nav.xml", '    <Navigate goal="2;0;0"/>')
    (result,) = run_cli(tmp_path, ["run", tree, "--world", world, "--quiet"])
    assert result["code"] == 1
    number = r"-?[0-9.]+"
    assert re.search(
        r"result: FAILURE \(Navigate: the occupancy grid would have 6,4[0-9,]+ cells "
        rf"\(80,0[0-9,]+ x 80,0[0-9,]+\): the world spans x {number}\.\.{number} m, "
        rf"y {number}\.\.{number} m \(obstacles plus margin\) at a resolution of 0\.05 m, and "
        r"bt-manip allows at most 25,000,000 cells; make the world smaller\)",
        result["out"],
    ), result["out"]


def test_navigate_in_a_world_at_the_grid_bound_stays_within_the_limits(tmp_path: Path) -> None:
    # a square room whose grid has 4,999 x 4,999 cells, just under the bound: the walls' outer
    # faces at +-124.465 m plus the 0.5 m margin span 249.93 m, 4,999 cells of 5 cm
    world = tmp_path / "big_room.yaml"
    h = 124.39
    walls = [("north", -h, h, h, h), ("south", -h, -h, h, -h), ("east", h, -h, h, h),
             ("west", -h, -h, -h, h), ("middle", 0, -100, 0, 100)]
    world.write_text(
        "name: big_room\nwalls:\n"
        + "".join(f"  - {{name: {n}, from: [{a}, {b}], to: [{c}, {d}], thickness: 0.15, "
                  "height: 1.5}\n" for n, a, b, c, d in walls)
        + "robots:\n  - {name: husky, description: husky_ur3, pose: [-60, 0, 0]}\n"
    )
    tree = _tree(tmp_path / "nav.xml", '    <Navigate goal="-58;0.5;0"/>')
    (result,) = run_cli(tmp_path, ["run", tree, "--world", world, "--quiet"])
    assert result["code"] == 0, result["out"]
    assert "result: SUCCESS" in result["out"]


def test_the_console_script_refuses_a_device_without_a_traceback(tmp_path: Path) -> None:
    done = subprocess.run(
        [sys.executable, "-m", "bt_manip.cli", "run", "/dev/zero"],
        preexec_fn=_limit_memory,
        capture_output=True,
        text=True,
        timeout=30,
        env=_env(),
        cwd=tmp_path,
    )
    assert done.returncode == 2
    assert done.stderr == "/dev/zero: file is a device, not a regular file\n"
    assert "Traceback" not in done.stdout


def test_bb_values_are_json_scalars_or_text() -> None:
    from bt_manip.cli import bb_value

    assert [bb_value(t) for t in ("1", "2.5", "true", '"1"', "-3")] == [1, 2.5, True, "1", -3]
    assert [bb_value(t) for t in ("kitchen", "[1, 2]", "null", "NaN", "")] == [
        "kitchen", "[1, 2]", "null", "NaN", ""]


def test_yaml_values_are_counted_with_aliases_expanded(tmp_path: Path) -> None:
    import pytest

    from bt_manip.errors import InputError
    from bt_manip.sim.yaml_lines import MAX_YAML_NODES, load_yaml

    # a list of n aliases to a 3-number list: 1 + n * 4 values, so n = 24,999 is the last fit
    def aliases(n: int) -> Path:
        path = tmp_path / f"aliases{n}.yaml"
        path.write_text("a: &a [0, 0, 0]\nb: [" + ", ".join(["*a"] * n) + "]\n")
        return path

    fits = (MAX_YAML_NODES - 1 - 2 - 4 - 1) // 4  # mapping, key a + its list, key b, list b
    assert len(load_yaml(aliases(fits))["b"]) == fits
    for n, line in ((fits + 1, 1), (MAX_YAML_NODES // 4, 2)):  # the whole file; list b alone
        with pytest.raises(InputError) as err:
            load_yaml(aliases(n))
        (problem,) = err.value.problems
        assert problem.line == line and "more than 100000 values" in problem.message
    looped = tmp_path / "looped.yaml"
    looped.write_text("a: &a [1, *a]\n")
    with pytest.raises(InputError) as err:
        load_yaml(looped)
    assert "an alias refers to a value that contains it" in str(err.value)
