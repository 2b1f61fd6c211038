"""Shared fixtures: corpus and oracle paths, golden files, hypothesis profiles."""

from __future__ import annotations

import json
import os
import signal
import sys
from pathlib import Path
from typing import Any

import pytest
from hypothesis import HealthCheck, settings

REPO = Path(__file__).resolve().parent.parent
SHARED = REPO.parent / "shared"
CORPUS = SHARED / "corpus"
ORACLES = SHARED / "oracles" / "cases.json"
SAMPLES = REPO / "samples"
GOLDEN = Path(__file__).resolve().parent / "golden"
#: The unit cube [0, 1]^3 as OBJ text, closed and wound outward (12 faces).
UNIT_CUBE_OBJ = """\
v 0 0 0
v 1 0 0
v 1 1 0
v 0 1 0
v 0 0 1
v 1 0 1
v 1 1 1
v 0 1 1
f 1 3 2
f 1 4 3
f 5 6 7
f 5 7 8
f 1 2 6
f 1 6 5
f 2 3 7
f 2 7 6
f 3 4 8
f 3 8 7
f 4 1 5
f 4 5 8
"""


def centred_cube_obj(half: float) -> str:
    """The cube [-half, half]^3 as OBJ text (no final newline), closed and wound outward."""
    return "\n".join(
        [f"v {x} {y} {z}" for x in (-half, half) for y in (-half, half) for z in (-half, half)]
        + ["f 1 2 4", "f 1 4 3", "f 5 7 8", "f 5 8 6", "f 1 5 6", "f 1 6 2"]
        + ["f 3 4 8", "f 3 8 7", "f 1 3 7", "f 1 7 5", "f 2 6 8", "f 2 8 4"]
    )


#: The tests mirror the package, a folder a room; the shared helpers (oracles.py,
#: strategies.py, ...) are here. A test imports a helper or another test module (its fixtures
#: and inputs: test_executor, test_cli_hull) by name: every folder is on sys.path, whichever
#: one pytest collects first.
TEST_FOLDERS = ("geometry", "io", "collision", "decomposition", "analysis", "targets", "cli")
for _folder in (Path(__file__).resolve().parent / name for name in TEST_FOLDERS):
    if str(_folder) not in sys.path:
        sys.path.append(str(_folder))

#: `meshcol decompose` flags that make CoACD fast enough for tests (coarse, few MCTS steps).
FAST_DECOMPOSE = [
    "--threshold",
    "0.2",
    "--resolution",
    "500",
    "-E",
    "mcts_iterations=20",
    "-E",
    "mcts_nodes=8",
    "-E",
    "mcts_max_depth=2",
]

# Hypothesis profiles (HYPOTHESIS_PROFILE): `nightly` runs the long example counts (150 a
# property, or the count its @settings names), `ci` (the default, `make test`) a third of each,
# `fast` (`make test-fast`) a sixth; those two are derandomized (repeatable runs), while
# `nightly` and `dev` draw new examples each run. The counts are scaled at collection
# (`_scale_examples`), so a test's own @settings(max_examples=N) is its nightly count.
EXAMPLES = 150
EXAMPLE_SCALE = {"nightly": 1.0, "dev": 1.0, "ci": 1 / 3, "fast": 1 / 6}
_quiet = {"deadline": None, "suppress_health_check": [HealthCheck.too_slow]}
settings.register_profile("nightly", max_examples=EXAMPLES, **_quiet)
settings.register_profile("ci", derandomize=True, max_examples=EXAMPLES, **_quiet)
settings.register_profile("dev", max_examples=400, deadline=None)
settings.register_profile("fast", derandomize=True, max_examples=EXAMPLES, **_quiet)
PROFILE = os.environ.get("HYPOTHESIS_PROFILE", "ci")
settings.load_profile(PROFILE)


def sized(count: int) -> int:
    """The input count of a property that does not draw through Hypothesis (a seeded batch
    checked against an oracle), scaled by the profile as the example counts are: ``count``
    under ``ci`` (``make test``), three times it under ``nightly``, half under ``fast``."""
    return max(1, round(count * 3 * EXAMPLE_SCALE.get(PROFILE, 1.0)))


def pytest_addoption(parser: pytest.Parser) -> None:
    parser.addoption("--update-golden", action="store_true", help="Rewrite tests/golden/ files.")


@pytest.fixture
def corpus() -> Path:
    """The shared corpus of real meshes (../shared/corpus); skips when absent."""
    if not CORPUS.is_dir():
        pytest.skip("shared corpus not present (../shared/corpus)")
    return CORPUS


@pytest.fixture(scope="session")
def oracle_cases() -> list[dict]:
    """The peer test cases in ../shared/oracles/cases.json; skips when absent."""
    if not ORACLES.is_file():
        pytest.skip("shared oracle cases not present (../shared/oracles/cases.json)")
    return json.loads(ORACLES.read_text())["cases"]


@pytest.fixture
def samples() -> Path:
    return SAMPLES


@pytest.fixture
def golden(request: pytest.FixtureRequest):
    """Compare text with tests/golden/NAME, or rewrite it under --update-golden."""

    def check(name: str, text: str) -> None:
        path = GOLDEN / name
        if request.config.getoption("--update-golden"):
            path.parent.mkdir(parents=True, exist_ok=True)
            path.write_text(text)
            return
        assert path.is_file(), f"golden file {path} missing: run pytest --update-golden"
        assert text == path.read_text(), f"output differs from golden {name}"

    return check


@pytest.fixture(autouse=True, scope="session")
def _private_user_cache(tmp_path_factory: pytest.TempPathFactory):
    """Tests never read or fill the user's real decompose cache (~/.cache/meshcol)."""
    previous = os.environ.get("XDG_CACHE_HOME")
    os.environ["XDG_CACHE_HOME"] = str(tmp_path_factory.mktemp("user-cache"))
    yield
    if previous is None:
        os.environ.pop("XDG_CACHE_HOME", None)
    else:
        os.environ["XDG_CACHE_HOME"] = previous


@pytest.fixture(scope="session")
def bowl_cache_home(tmp_path_factory: pytest.TempPathFactory) -> Path:
    """An ``XDG_CACHE_HOME`` of the run's own (its decompose cache is
    ``meshcol/decompose`` in it), shared by the two tests that decompose samples/bowl/bowl.obj
    with CoACD's default parameters (about 17 s of CPU): the check of the ball in the bowl
    (tests/analysis/test_check.py) and the README tour's ``meshcol decompose`` line
    (tests/test_readme.py). Whichever runs first computes the parts, the other reads them
    from the cache (:data:`XDIST_GROUPS` keeps the two files on one worker)."""
    return tmp_path_factory.mktemp("bowl-cache-home")


#: Tests of more than about two seconds on 2 cores (``--durations``): ``make test-fast``
#: leaves them out with ``-m "not slow"``; ``make test`` runs everything. Tests on the shared
#: corpus are slow too (marked from their fixtures below).
SLOW_TESTS = {
    # 0.6-1.3 s each in the fast lane (session 40: a fresh clone's took 39.4-41.4 s, at its
    # 40 s, after the helpers' tests): the full lane keeps them
    "test_a_many_polygon_vertex_is_fitted_within_the_plane_cap",
    "test_workers_never_import_a_meshcol_folder_of_the_working_folder",
    "test_resume_with_other_options_or_no_manifest_is_an_error",
    "test_pictures_show_the_pair_framed_with_witnesses_and_normal",
    "test_check_target_findings_are_cases_as_the_exit_code_counts_them",
    "test_help_uri_points_into_the_rules_page_under_the_configured_base",
    # 1.45 s in the fast lane (session 39, which had reached 40.25 s): the full lane keeps it
    "test_no_module_tests_manifest_extensions_itself",
    # over 1.4 s each in the fast lane (session 5): kept in the full lane
    "test_rotated_grids_keep_the_invariants",
    "test_groups_drop_exactly_the_pairs_within_a_group",
    "test_progress_heartbeat_shows_a_long_silent_step",
    "test_hierarchy_of_denormal_and_huge_vertices_builds_without_crashing",
    "test_fine_uv_sphere_does_not_self_intersect",
    "test_fast_check_passes_the_valid_common_documents",
    "test_the_column_path_loads_what_the_body_by_body_path_loads",
    "test_any_shape_spinning_about_a_pivot_matches_dense_sampling",
    "test_spin_matches_dense_sampling",
    "test_ball_in_bowl_is_separated_when_decomposed",
    "test_incremental_sweep_with_grid_cells_equals_brute_force",
    "test_timeout_stops_one_file_and_the_others_finish",
    "test_triangle_distance_matches_numpy_oracle_on_random_pairs",
    "test_jobs_two_gives_the_same_output_as_jobs_one",
    "test_larger_sets_use_the_grid_and_equal_brute_force",
    "test_killed_run_leaves_no_cache_entry_or_output",
    "test_vhacd_engine_budgets",
    "test_vhacd_engine",
    "test_same_input_gives_identical_bytes_and_cache_hit_is_fast",
    "test_tree_against_tree_equals_brute_force",
    "test_incremental_sweep_equals_brute_force_over_steps",
    "test_parts_are_convex_and_cover_the_torus",
    "test_short_fuzzing_run_finds_nothing",
    "test_signals_stop_the_run_and_leave_nothing",
    "test_max_hausdorff_gates_what_sticks_out_not_the_cuts",
    # session 6: the fast lane reached 59 s with the new tests; the slowest go here
    "test_decompose_then_check_reuses_the_cache_part_by_part",
    "test_lattice_of_touching_unit_cubes_uses_threads_and_grid",
    "test_random_clouds_equal_qhull_and_keep_the_invariants",
    "test_worker_pool_reads_tasks_ahead_and_fails_fast",
    "test_bvh_distance_equals_brute_force_over_triangle_pairs",
    "test_denormal_scale_is_a_one_line_error_not_a_crash",
    "test_structured_box_family_distance_and_depth_exact",
    "test_each_profile_brings_a_fine_sphere_within_its_counts",
    "test_containment_of_disjoint_pairs_equals_the_exact_winding_number",
    # over 1 s each in the fast lane (session 7, which took it to 58 s): the full lane
    "test_exact_ray_crossings_agree_with_the_winding_number",
    "test_rotated_near_pairs_equal_brute_force",
    "test_hull_target_physx_gpu_meets_every_limit_and_encloses",
    "test_parts_layout_and_report",
    "test_all_structures_equal_brute_force",
    "test_box_query_equals_brute_force",
    "test_batch_equals_loop_of_singles",
    "test_fast_winding_number_is_within_its_bound",
    "test_columns_pass_only_what_the_body_by_body_check_passes",
    "test_ray_cast_equals_brute_force",
    "test_resting_contact_under_any_rigid_motion_is_never_penetrating",
    "test_decompose_robot_target_that_cannot_be_met_names_the_rule",
    # session 8: the fast lane reached 50 s (60 s with its install); the slowest go here
    "test_hull_target_that_cannot_be_met_exits_1_with_the_rule_id",
    "test_combined_ucx_and_glb_layouts",
    "test_every_profile_meets_its_limits_or_says_which",
    "test_nested_meshes_without_crossing",
    # session 26: the fast lane took 45-51 s of tests on a quiet 2-core machine; these three
    # took 3.2-4.8 s each (two wait on timed fake steps in a child process)
    "test_single_file_line_shows_time_left_on_a_terminal",
    "test_no_progress_lines_off_a_terminal",
    "test_results_keep_no_memory_or_references",
    # session 28: they run the CLI with a worker pool, 1.1-1.7 s each in the fast lane (load
    # 3.5), where a fresh clone's lane had measured 42-45 s in session 27
    "test_changed_since_runs_what_a_commit_touched",
    "test_the_pool_gives_the_report_of_one_process",
    "test_search_off_only_checks",
    # session 39: `meshcol inspect` on each of the 300 COLLADA files of the robots-wild
    # extras, about a minute (a fast subset, test_wild_dae_files_inspect_cleanly, stays)
    "test_every_wild_dae_file_inspects_cleanly",
}


#: Work units of ``make test``'s two workers (``-n 2 --dist loadgroup``): each test alone,
#: except the files named here, whose tests run on one worker, in order, as one unit. The
#: Ray tests start Ray clusters on 127.0.0.1 (one at a time: test_ray_cluster.py
#: joins only its own); the others have a module fixture worth computing once (the whole
#: corpus inspected and hulled; a CoACD torus; the package's sources parsed once, for
#: the files that check rules on them: tests/package_source.py), or share a session one
#: (the bowl's CoACD parts: :func:`bowl_cache_home`).
XDIST_GROUPS = {
    "test_ray.py": "ray",
    "test_ray_cluster.py": "ray",
    "test_ray_local.py": "ray",
    "test_cli_inspect.py": "test_cli_inspect.py",
    "test_decompose.py": "test_decompose.py",
    "test_architecture.py": "package_source",
    "test_code_size.py": "package_source",
    "test_inputs.py": "package_source",
    "test_check.py": "bowl",
    "test_readme.py": "bowl",
}


def pytest_configure(config: pytest.Config) -> None:
    # A shell starts a background job (`make test &`, nohup) with SIGINT ignored, and Python
    # then leaves it ignored: the tests of what Ctrl-C does would see no KeyboardInterrupt.
    # Run them as from a terminal (each xdist worker configures itself too).
    if signal.getsignal(signal.SIGINT) is signal.SIG_IGN:
        signal.signal(signal.SIGINT, signal.default_int_handler)
    if config.pluginmanager.hasplugin("xdist"):
        config.pluginmanager.register(_XdistGroups(), "meshcol-xdist-groups")


class _XdistGroups:
    """``--dist loadgroup`` by :data:`XDIST_GROUPS`. (xdist's own reads ``xdist_group``
    marks through ``item._nodeid``, which pytest 9 no longer reads: its groups split.)"""

    @staticmethod
    def pytest_xdist_make_scheduler(config: pytest.Config, log: Any) -> Any:
        if config.getvalue("dist") != "loadgroup":
            return None
        from xdist.scheduler import LoadScopeScheduling

        class Scheduling(LoadScopeScheduling):
            def _split_scope(self, nodeid: str) -> str:
                name = nodeid.split("::", 1)[0].rsplit("/", 1)[-1]
                return XDIST_GROUPS.get(name, nodeid)

        return Scheduling(config, log)


@pytest.hookimpl(tryfirst=True)
def pytest_collection_modifyitems(config: pytest.Config, items: list[pytest.Item]) -> None:
    slow = pytest.mark.slow
    scaled: set[int] = set()
    for item in items:
        fixtures = set(getattr(item, "fixturenames", ()))
        if item.originalname in SLOW_TESTS or fixtures & {"corpus", "corpus_run"}:  # type: ignore[attr-defined]
            item.add_marker(slow)
        _scale_examples(item, EXAMPLE_SCALE.get(PROFILE, 1.0), scaled)


def _scale_examples(item: pytest.Item, scale: float, scaled: set[int]) -> None:
    """The profile's share of a property's example count (its @settings or the profile's)."""
    if scale == 1.0:
        return
    test = getattr(getattr(item, "obj", None), "__func__", getattr(item, "obj", None))
    owner = getattr(item, "cls", None)
    if hasattr(test, "hypothesis"):  # @given: the settings Hypothesis reads when it runs
        holder, name = test, "_hypothesis_internal_use_settings"
    elif isinstance(getattr(owner, "settings", None), settings):  # a state machine's TestCase
        holder, name = owner, "settings"
    else:
        return
    current = getattr(holder, name, None)
    if current is None or id(holder) in scaled:
        return
    scaled.add(id(holder))
    setattr(
        holder, name, settings(current, max_examples=max(2, round(current.max_examples * scale)))
    )


def pytest_terminal_summary(terminalreporter, exitstatus: int, config: pytest.Config) -> None:
    """Say loudly, at the end of the run, how many tests skipped for want of ../shared."""
    skipped = terminalreporter.stats.get("skipped", [])
    missing = [r for r in skipped if "../shared" in str(getattr(r, "longrepr", ""))]
    if missing:
        terminalreporter.write_sep(
            "!",
            f"WARNING: {SHARED} is absent or incomplete: {len(missing)} tests SKIPPED "
            "(real-mesh corpus and oracle cases); put the shared folder beside the repository",
            red=True,
            bold=True,
        )
