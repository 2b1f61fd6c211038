"""The engine's own steps on the progress line (issue 29 item 18): a worker reports each step
to the parent, and a single-file run shows an honest time left on a terminal, none off one.
(A Ray task's steps: tests/test_ray.py, on that module's Ray.)"""

from __future__ import annotations

import os
import pty
import re
import select
import subprocess
import sys
import textwrap
import time
from pathlib import Path

from meshcol.decomposition.steps import (
    ProgressText,
    StepClock,
    describe,
    reporting_to,
    stage,
)


class _Clock:
    def __init__(self) -> None:
        self.now = 0.0

    def __call__(self) -> float:
        return self.now


def test_no_time_left_until_a_step_has_finished() -> None:
    clock = _Clock()
    steps = StepClock(clock)
    steps.update((("search step", 0, 10, True, None),))
    clock.now = 30.0
    assert steps.left() is None  # nothing finished: no number
    steps.update((("search step", 1, 10, True, None),))  # one step took 30 s
    left = steps.left()
    assert left is not None
    # the current step (30 s on average) and the 8 more the budget allows (flagged: a budget)
    assert left == (270.0, True)
    clock.now = 40.0
    assert steps.left() == (260.0, True)  # counts down between reports
    clock.now = 500.0  # far past the average: the step under way raises it, never negative
    seconds, _ = steps.left() or (None, None)
    assert seconds is not None and seconds == 8 * 250.0


def test_nested_stages_take_the_inner_estimate_for_the_unit_under_way() -> None:
    clock = _Clock()
    steps = StepClock(clock)
    steps.update((("body", 0, 2, False, "a"), ("search step", 0, 4, False, None)))
    clock.now = 10.0
    steps.update((("body", 0, 2, False, "a"), ("search step", 1, 4, False, None)))
    # body a: three steps of 10 s left; body b's time is unknown (no body has finished)
    assert steps.left() is None
    clock.now = 40.0
    steps.update((("body", 1, 2, False, "b"),))
    clock.now = 41.0
    steps.update((("body", 1, 2, False, "b"), ("search step", 0, 4, False, None)))
    # the last body under way: 40 s a body, 1 s in: 39 s (the inner stage has no step yet)
    assert steps.left() == (39.0, False)
    clock.now = 45.0
    steps.update((("body", 1, 2, False, "b"), ("search step", 1, 4, False, None)))
    assert steps.left() == (12.0, False)  # three steps of 4 s


def test_a_stage_without_a_total_gives_no_number() -> None:
    clock = _Clock()
    steps = StepClock(clock)
    steps.update((("CoACD", 0, None, False, None),))
    clock.now = 100.0
    assert steps.left() is None
    assert describe((("body", 1, 3, False, "gear"), ("CoACD", 0, None, False, None))) == (
        "body 2/3 (gear), CoACD"
    )


def test_reports_reach_the_sink_and_never_fail_the_work() -> None:
    seen = []
    with reporting_to(seen.append), stage("search step", at_most=3) as s:
        s.advance()
    assert seen == [
        (("search step", 0, 3, True, None),),
        (("search step", 1, 3, True, None),),
        (),
    ]

    def broken(snapshot: object) -> None:
        raise OSError("pipe closed")

    with reporting_to(broken), stage("x", 2) as s:
        s.advance()  # dropped, not raised
    text = ProgressText("decompose: 0/1 files", lambda: (5.0, False))
    assert text == "decompose: 0/1 files" and text.time_left() == (5.0, False)


# ---------------------------------------------------------------------------------------------
# end to end: `meshcol decompose one.obj`, its worker's steps slowed down

_FAKE_ENGINE = '''
import os
import time

from meshcol.decomposition.steps import stage
from meshcol.decomposition.tasks import decompose_task


def slow_task(task):
    """The real task, after three slow steps reported as the engine's own."""
    with stage("fake step", 3) as steps:
        for _ in range(3):
            time.sleep(float(os.environ["FAKE_STEP_SECONDS"]))
            steps.advance()
    return decompose_task(task)
'''

_RUN = """
import functools, sys
import fake_engine
import meshcol.cli.decompose as command
import meshcol.decomposition.batch as batch
from meshcol.cli import main

if __name__ == "__main__":  # the workers' fork server imports this file as __main__
    batch.worker_entry = lambda options: fake_engine.slow_task
    command.Progress = functools.partial(command.Progress, delay=0.0)
    sys.argv = ["meshcol", "decompose", "cube.obj", "-o", "parts", "--no-cache"]
    main()
"""


def _cube(path: Path) -> None:
    corners = [(x, y, z) for x in (0, 1) for y in (0, 1) for z in (0, 1)]
    faces = [
        (1, 3, 4), (1, 4, 2), (5, 6, 8), (5, 8, 7), (1, 2, 6), (1, 6, 5),
        (3, 7, 8), (3, 8, 4), (1, 5, 7), (1, 7, 3), (2, 4, 8), (2, 8, 6),
    ]  # fmt: skip
    lines = [f"v {x} {y} {z}" for x, y, z in corners] + [f"f {a} {b} {c}" for a, b, c in faces]
    path.write_text("\n".join(lines) + "\n")


def _workspace(tmp_path: Path, seconds: float) -> dict[str, str]:
    (tmp_path / "fake_engine.py").write_text(_FAKE_ENGINE)
    (tmp_path / "run.py").write_text(textwrap.dedent(_RUN))
    _cube(tmp_path / "cube.obj")
    # the workers import fake_engine too
    env = {**os.environ, "PYTHONPATH": str(tmp_path), "FAKE_STEP_SECONDS": str(seconds)}
    env.pop("MESHCOL_PROGRESS", None)
    return env


def test_single_file_line_shows_time_left_on_a_terminal(tmp_path: Path) -> None:
    env = _workspace(tmp_path, 0.8)
    leader, follower = pty.openpty()
    process = subprocess.Popen(
        [sys.executable, "run.py"],
        cwd=tmp_path,
        env=env,
        stdin=subprocess.DEVNULL,
        stdout=subprocess.PIPE,
        stderr=follower,
    )
    os.close(follower)
    screen = b""
    deadline = time.monotonic() + 120  # a bound for a loaded machine, not a speed
    while time.monotonic() < deadline:
        ready, _, _ = select.select([leader], [], [], 1.0)
        if ready:
            try:
                chunk = os.read(leader, 65536)
            except OSError:  # the pty closes when the command exits
                break
            if not chunk:
                break
            screen += chunk
        elif process.poll() is not None:
            break
    process.communicate(timeout=60)
    os.close(leader)
    assert process.returncode == 0, screen.decode(errors="replace")
    lines = [line for line in screen.decode(errors="replace").split("\r\033[K") if line]
    stepping = [line for line in lines if "fake step" in line]
    assert stepping, lines
    # before the first step ends: where the file is and its elapsed time, no number
    first = stepping[0]
    assert "fake step 1/3" in first and "left" not in first, first
    # after it: an estimate, in "about" words, never negative
    later = [line for line in stepping if re.search(r"about \d+ s left\)", line)]
    assert later, stepping
    assert all("fake step 1/3" not in line for line in later)
    assert not any(re.search(r"-\d+ s left", line) for line in lines)


def test_no_progress_lines_off_a_terminal(tmp_path: Path) -> None:
    env = _workspace(tmp_path, 0.3)
    result = subprocess.run(
        [sys.executable, "run.py"],
        cwd=tmp_path,
        env=env,
        stdin=subprocess.DEVNULL,
        capture_output=True,
        text=True,
        timeout=180,
    )
    assert result.returncode == 0, result.stderr
    assert "fake step" not in result.stderr
    assert "elapsed" not in result.stderr and "left" not in result.stderr
