"""evaluate(split=FILE, pool=FILE): a generated split or pool of any name and location runs; the job is
identified by the manifest's content hash and records the file's path, not hashed."""
import json
import os
import shutil
import sys

import pytest

import actionshift

sys.path.insert(0, os.path.dirname(__file__))
import simple_policy  # noqa: E402


@pytest.fixture
def custom_files(tmp_path, cli):
    gen = tmp_path / "gen"
    cli("splits", "generate", "--seed", "7", "--rule", "seen", "--rule", "full", "--out", str(gen), check=0)
    cli("validate", str(gen / "seen.json"), check=0)
    where = tmp_path / "my dir"
    where.mkdir()
    split, pool = where / "custom-split.json", where / "custom pool.json"  # any name: validate's file-name rule is not the job's
    shutil.move(gen / "seen.json", split)
    shutil.move(gen / "full.json", pool)
    return split, pool


def test_evaluate_runs_a_split_file_of_any_name(tmp_path, cli, custom_files):
    split, pool = custom_files
    out = tmp_path / "out"
    r = actionshift.evaluate(simple_policy.ReachGraspLift(), task="pick_cube", split=split, method="no_adapt",
                             seed=3, episodes=2, out=str(out))
    assert r["episodes_run"] == 2
    summary = json.loads((out / f"{r['job_id']}.summary.json").read_text())
    assert summary["job"]["split"]["path"] == str(split)
    assert summary["job"]["split"]["sha256"] == actionshift.load_manifest(str(split)).manifest_sha256
    assert "path" not in r["job"]["split"]  # the identity object: the path is recorded, not hashed
    # the same manifest elsewhere is the same job
    moved = tmp_path / "moved.json"
    shutil.copy(split, moved)
    again = actionshift.evaluate(simple_policy.ReachGraspLift(), task="pick_cube", split=str(moved), method="no_adapt",
                                 seed=3, episodes=2, out=str(out))
    assert again["already_complete"] and again["job_id"] == r["job_id"]
    # and the CLI reaches the same job from the file
    p = cli("run", "--task", "pick_cube", "--split", str(split), "--method", "oracle", "--seed", "3", "--episodes", "1",
            "--out", str(tmp_path / "cli"), "--progress", "off", check=0)
    assert p.stdout.split()[1] == "pick_cube/seen/oracle"


def test_evaluate_runs_a_pool_file(tmp_path, custom_files):
    split, pool = custom_files
    r = actionshift.evaluate(simple_policy.ReachGraspLift(), task="pick_cube", split=str(split), pool=pool,
                             method="entropy_probes", seed=3, episodes=1, out=str(tmp_path / "out"))
    assert r["episodes_run"] == 1
    summary = json.loads(open(r["summary_path"]).read())
    assert summary["job"]["pool"]["path"] == str(pool)
    assert "path" not in r["job"]["pool"]
