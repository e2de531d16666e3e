"""Contracts, decoder, manifests and pools from Python, with hash parity against the CLI."""
import json
import os

import numpy as np
import pytest

import actionshift

IDENTITY_SHA = "6b38e10f94c37daf6ec3027f9fade885c611bbf710b732cc6f61ed134efb1eaa"
REFERENCE9_POOL_SHA = "b177b082925800655dee9e93c02142f26a703fd2bdf1d97be56a2cb0bf0eeea3"


def test_identity_contract_hash_and_json_round_trip():
    c = actionshift.Contract.identity()
    assert c.hash() == c.sha256 == IDENTITY_SHA
    assert actionshift.Contract.from_json(c.to_json()) == c
    assert actionshift.Contract.from_json(c.to_dict()) == c
    lagged = actionshift.Contract(permutation=[1, 0, 2, 3, 4, 5], lag=2, target="absolute")
    assert lagged.lag == 2 and lagged.target == "absolute" and list(lagged.permutation) == [1, 0, 2, 3, 4, 5]
    assert lagged.composition_signature() == ["permutation", "target", "lag"]
    assert lagged != c and len({c, lagged, actionshift.Contract()}) == 2


def test_contract_hashes_equal_the_cli(cli):
    contracts = actionshift.load_manifest("seen").contracts + actionshift.load_manifest("reference9").contracts
    lines = "".join(json.dumps({"contract": c.to_dict()}) + "\n" for c in contracts)
    out = cli("contract", "hash", stdin=lines, check=0).stdout.split()
    cli_hashes = [json.loads(line)["sha256"] for line in out]
    assert cli_hashes == [c.hash() for c in contracts]
    assert len(set(cli_hashes)) == len(contracts)


def test_manifest_and_pool_hashes_equal_cli_validate(cli, source_dir):
    report = json.loads(cli("validate", "--json", os.path.join(source_dir, "manifests"), check=0).stdout)
    by_name = {m["name"]: m for m in report["manifests"]}
    assert sorted(by_name) == actionshift.builtin_manifests()
    for name, m in by_name.items():
        py = actionshift.load_manifest(os.path.join(source_dir, "manifests", name + ".json"))
        assert py.name == name and py.kind == m["kind"] and len(py) == m["contracts"]
        assert py.manifest_sha256 == py.computed_sha256() == m["manifest_sha256"]
        assert py.pool_sha256 == m["pool_sha256"]
        assert all(c["ok"] for c in py.validate(regenerate=False))
    pool = actionshift.load_manifest("reference9")
    assert pool.pool_sha256 == REFERENCE9_POOL_SHA == actionshift.pool_sha256(pool.contracts)


def test_tampered_manifest_fails_validation(tmp_path, source_dir):
    text = open(os.path.join(source_dir, "manifests", "reference9.json")).read()
    bad = tmp_path / "reference9.json"
    bad.write_text(text.replace('"scale":[1.0', '"scale":[1.5', 1))
    # a manifest file is verified when it is loaded: the tampered copy is refused, naming the check
    with pytest.raises(actionshift.InputError, match="record_hashes: check failed"):
        actionshift.load_manifest(str(bad))


def test_decode_encode_match_the_cli(cli):
    c = actionshift.Contract(permutation=[2, 0, 1, 3, 5, 4], sign=[1, -1, 1, 1, 1, -1],
                             scale=[0.5, 1, 2, 1, 1, 1], frame="tool", gripper_inverted=True)
    R = np.array([[0.0, -1.0, 0.0], [1.0, 0.0, 0.0], [0.0, 0.0, 1.0]])
    raw = np.array([0.1, -0.2, 0.3, 0.05, -0.4, 0.25, 0.7])
    canonical = actionshift.decode(c, raw, R)
    req = {"contract": c.to_dict(), "raw": raw.tolist(), "rotation": R.tolist()}
    cli_out = json.loads(cli("contract", "decode", json.dumps(req), check=0).stdout)
    assert np.allclose(canonical, cli_out["canonical"], rtol=0, atol=1e-15)
    assert np.allclose(actionshift.encode(c, canonical, R), raw, atol=1e-12)
    J = actionshift.decode_jacobian(c, R)
    assert np.allclose(J @ raw, canonical, atol=1e-12)


def test_decoder_lag_fifo_and_batch():
    c = actionshift.Contract(lag=2)
    d = actionshift.Decoder(c)
    outs = [d.step(np.full(7, k + 1.0) * 0.1, reset=(k == 0)) for k in range(4)]
    assert np.all(outs[0] == 0) and np.all(outs[1] == 0)
    assert np.allclose(outs[2], 0.1) and np.allclose(outs[3], 0.2)
    batch = actionshift.Decoder(actionshift.Contract(sign=[-1, 1, 1, 1, 1, 1]), num_envs=3)
    raw = np.arange(21, dtype=float).reshape(3, 7) / 100
    out = batch.step_batch(raw)
    assert out.shape == (3, 7) and np.allclose(out[:, 0], -raw[:, 0]) and np.allclose(out[:, 1:], raw[:, 1:])


def test_bad_contract_raises_value_error_with_the_cli_message(cli):
    bad = {"frame": "base", "gripper_inverted": False, "lag": 0, "permutation": [0, 0, 2, 3, 4, 5],
           "scale": [1.0] * 6, "sign": [1] * 6, "target": "delta"}
    with pytest.raises(ValueError) as e:
        actionshift.Contract.from_json(bad)
    assert isinstance(e.value, actionshift.InputError)
    assert e.value.reason == "permutation must be a bijection over component indices"
    p = cli("contract", "hash", json.dumps({"contract": bad}))
    assert p.returncode == 2
    line = p.stderr.strip()
    assert line.startswith("actionshift: error: ") and line.endswith(str(e.value)), (line, str(e.value))
    for text in ["{not json", '{"lag": 1}', "[]"]:
        with pytest.raises(ValueError):
            actionshift.Contract.from_json(text)
    with pytest.raises(ValueError, match="scale values must be finite and positive"):
        actionshift.Contract(scale=[1, 1, 0, 1, 1, 1])
    with pytest.raises(ValueError, match="raw: must be 7 numbers"):
        actionshift.decode(actionshift.Contract(), [1, 2, 3])
    with pytest.raises(ValueError, match="not orthonormal"):
        actionshift.decode(actionshift.Contract(), np.zeros(7), np.ones((3, 3)))


def test_bad_manifest_file_raises_the_cli_message(tmp_path, cli):
    bad = tmp_path / "broken.json"
    bad.write_text('{"schema_version": "9"}')
    with pytest.raises(ValueError) as e:
        actionshift.load_manifest(str(bad))
    p = cli("validate", str(bad))
    assert p.returncode == 2
    assert p.stderr.strip() == "actionshift: error: " + str(e.value)
    assert e.value.source == str(bad)


@pytest.mark.parametrize("raw", ["x", None, object(), [[1, "a"]]])
def test_decoder_batch_input_that_is_not_numbers_is_a_value_error(raw):
    # the batch path used to dereference the null array pybind11 returns for such input (segfault)
    d = actionshift.Decoder(actionshift.Contract.identity(), num_envs=2)
    with pytest.raises(ValueError, match="raw: "):
        d.step_batch(raw)
    with pytest.raises(ValueError, match="R: "):
        d.step_batch(np.zeros((2, 7)), R="x")
    with pytest.raises(ValueError, match="reset_mask: must be 2 booleans"):
        d.step_batch(np.zeros((2, 7)), reset_mask=object())


def test_tcp_slices_need_an_observation_of_exactly_that_task():
    # a peg observation (43 numbers) read as pick_cube's (42) used to give a plausible wrong rotation
    obs = actionshift.make("peg_insertion_side").reset(seed=1)[0]
    assert actionshift.tcp_rotation(obs, "peg_insertion_side").shape == (3, 3)
    with pytest.raises(ValueError, match=r"obs: not an observation of pick_cube \(expected shape \(42,\)"):
        actionshift.tcp_rotation(obs, "pick_cube")
    with pytest.raises(ValueError, match="its TCP quaternion is zero"):
        actionshift.tcp_rotation(np.zeros(obs.shape), "peg_insertion_side")
    with pytest.raises(ValueError, match="prev_obs: must be finite"):
        actionshift.tcp_response(np.full(obs.shape, np.nan), obs, "peg_insertion_side")


def test_decoder_sizes_and_contract_dict_errors_are_one_line():
    with pytest.raises(ValueError, match=r"num_envs x \(lag \+ 1\) must be at most 16777216"):
        actionshift.Decoder(actionshift.Contract(lag=1024), num_envs=10 ** 5)
    with pytest.raises(ValueError, match=r"num_envs: must be an integer in \[1, "):
        actionshift.Decoder(actionshift.Contract(), num_envs=2 ** 40)
    bad = {"frame": "base", "gripper_inverted": False, "lag": 0, "permutation": [0, 1, 2, 3, 4, 5],
           "scale": [float("nan")] + [1.0] * 5, "sign": [1] * 6, "target": "delta"}
    with pytest.raises(ValueError, match=r"^contract: NaN and infinity are not allowed"):
        actionshift.make("pick_cube", contract=bad)
    with pytest.raises(ValueError) as e:
        actionshift.Contract.from_json("{")
    assert not str(e.value).startswith("contract: contract:")


def test_an_int_too_large_for_its_parameter_is_out_of_range_not_a_type_error():
    # was "Contract(): lag: expected an int (got int)"
    for call, field in [(lambda: actionshift.Contract(lag=2 ** 63), "lag"),
                        (lambda: actionshift.Contract(permutation=[2 ** 64, 1, 2, 3, 4, 5]), "permutation"),
                        (lambda: actionshift.SelfTest(budget=2 ** 40), "budget")]:
        with pytest.raises(ValueError) as e:
            call()
        assert f"(): {field}: out of range: " in str(e.value), str(e.value)
        assert "is too large in magnitude" in str(e.value)
        assert "\n" not in str(e.value)


@pytest.mark.parametrize("call, message", [
    (lambda: actionshift.Contract(1, 2, 3), "Contract(): permutation: expected a sequence of 6 integers (got int)"),
    (lambda: actionshift.Contract(lag="2"), "Contract(): lag: expected an int (got str)"),
    (lambda: actionshift.Contract(perm=[0, 1, 2, 3, 4, 5]), "Contract(): unknown keyword argument 'perm' (known: permutation,"),
    (lambda: actionshift.Contract([0, 1, 2, 3, 4, 5], permutation=[0, 1, 2, 3, 4, 5]),
     "Contract(): 'permutation' given twice (by position and by keyword)"),
    (lambda: actionshift.Contract(*range(8)), "Contract(): takes at most 7 arguments"),
    (lambda: actionshift.SelfTest(budget="6"), "SelfTest(): budget: expected an int (got str)"),
    (lambda: actionshift.SelfTest(amplitude=None), "SelfTest(): amplitude: expected a number (got NoneType)"),
    (lambda: actionshift.SelfTest(budjet=6), "SelfTest(): unknown keyword argument 'budjet'"),
])
def test_constructor_calls_that_match_no_signature_are_one_line_type_errors(call, message):
    # pybind11's own message lists every signature over several lines
    with pytest.raises(TypeError) as e:
        call()
    assert str(e.value).startswith(message), str(e.value)
    assert "\n" not in str(e.value)
    # valid calls build the same objects whichever overload binds them: a call that needs a
    # conversion (integers for floats) is bound by the catch-all overload, with the same defaults
    assert actionshift.Contract(lag=2).lag == 2
    assert actionshift.Contract(scale=[1, 1, 1, 1, 1, 1]).hash() == actionshift.Contract().hash() \
        == actionshift.Contract.identity().hash()
    assert actionshift.Contract(scale=[0.5, 1, 2, 1, 1, 1]).scale == [0.5, 1.0, 2.0, 1.0, 1.0, 1.0]
    assert actionshift.SelfTest(amplitude=1).verdict() == actionshift.SelfTest(amplitude=1.0).verdict()


def test_wilson_interval_is_the_engines(cli):
    # the same numbers as Gate 0's verdict file for the same counts (the reference's 0/600 lower bound is 0.0)
    w = actionshift.wilson_interval(297, 300)
    assert w["successes"] == 297 and w["total"] == 300 and abs(w["rate"] - 0.99) < 1e-15
    assert round(w["lower"], 3) == 0.971 and round(w["upper"], 3) == 0.997
    assert actionshift.wilson_interval(0, 600)["lower"] == 0.0
    for bad in ((1, 0), (-1, 5), (6, 5)):
        with pytest.raises(ValueError, match="wilson_interval"):
            actionshift.wilson_interval(*bad)
