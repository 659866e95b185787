"""The streaming filter equals the offline run; the track export and its covariance."""

from __future__ import annotations

import numpy as np
import pytest
from testdata import DATA

from pednav_env.io import Recording, load_recording, to_uniform
from pednav_env.replay.runner import prepare, run_prepared
from pednav_env.replay.setup import named_setup
from pednav_env.replay.stream import ZuptStream
from pednav_env.replay.track import TRACK_COLUMNS, run_states, write_track_csv

PYSHOE = DATA / "replay" / "pyshoe_2017-11-22-11-48-35_first7s.mat"
HALLWAY = DATA / "hallway" / "SensorConnectData_31_first9s_LLIO.mat"
#: Blocking changes only rounding (ZuptUkf.advance, tested there); over a few
#: seconds the positions of the offline and the streamed run agree to 1e-7 m.
ROUNDING_M = 1e-6


def feed_in_blocks(stream: ZuptStream, rec: Recording, seed: int):
    """Feed the recording's uniform samples in random blocks of 1–40 samples."""
    u = to_uniform(rec)
    rng = np.random.default_rng(seed)
    outs, i = [], 0
    while i < u.num_samples:
        k = int(rng.integers(1, 41))
        outs.append(stream.feed(u.omega_b[i : i + k], u.f_b[i : i + k]))
        i += k
    return outs


@pytest.mark.parametrize("path", [PYSHOE, HALLWAY])
@pytest.mark.parametrize("setup", ["real-fixed", "paper"])
def test_streaming_in_blocks_equals_the_offline_run(path, setup):
    rec = load_recording(path)
    prep = prepare(rec, named_setup(setup))
    offline = run_prepared(prep)
    stream = ZuptStream(prep.rate_hz, setup)
    outs = feed_in_blocks(stream, rec, seed=1)
    assert len(outs[0]) == 0  # the first samples wait for the still start
    pos = np.concatenate([o.position_m for o in outs])
    stance = np.concatenate([o.stance for o in outs])
    nav = np.concatenate([o.navigating for o in outs])
    sample = np.concatenate([o.sample for o in outs])
    np.testing.assert_array_equal(sample, np.arange(prep.num_samples))
    np.testing.assert_allclose(pos, offline.pos[0], atol=ROUNDING_M, rtol=0)
    np.testing.assert_array_equal(stance, offline.stance[0])
    assert nav.sum() == prep.num_samples - prep.n_align
    assert stream.n_align == prep.n_align and stream.skipped == 0
    np.testing.assert_allclose(stream.state.position_m[0], offline.pos[0, -1], atol=ROUNDING_M)


def test_a_settling_start_is_skipped_as_offline():
    rec = load_recording(PYSHOE)
    w = rec.omega_b.copy()
    w[:30, 1] += 0.4  # rad/s: the foot moves during the first 0.15 s
    moved = Recording(rec.time, w, rec.f_b, name="settling")
    prep = prepare(moved, named_setup("real-fixed"))
    assert prep.skipped > 0
    offline = run_prepared(prep)
    stream = ZuptStream(prep.rate_hz, "real-fixed")
    outs = feed_in_blocks(stream, moved, seed=2)
    pos = np.concatenate([o.position_m for o in outs])
    assert stream.skipped == prep.skipped and stream.n_align == prep.n_align
    np.testing.assert_allclose(pos[prep.skipped :], offline.pos[0], atol=ROUNDING_M, rtol=0)
    assert not np.concatenate([o.navigating for o in outs])[: prep.skipped + prep.n_align].any()


def test_covariance_and_knobs_follow_the_offline_track():
    rec = load_recording(PYSHOE)
    prep = prepare(rec, named_setup("real-fixed"))
    offline = run_prepared(prep, knobs={"shoe_threshold": [1e7]}, track=True)
    stream = ZuptStream(prep.rate_hz, "real-fixed", covariance=True)
    stream.set_knobs(shoe_threshold=1e7)  # kept until the alignment
    outs = feed_in_blocks(stream, rec, seed=3)
    cov = np.concatenate([o.covariance_diag for o in outs])
    x = np.concatenate([o.position_m for o in outs])
    np.testing.assert_allclose(x, offline.states[0, :, :3], atol=ROUNDING_M, rtol=0)
    np.testing.assert_allclose(cov, offline.covariance_diag[0], rtol=1e-6, atol=1e-15)
    # the position variance grows between ZUPTs and is reset by them
    var = cov[prep.n_align :, 0]
    assert var.max() > 10 * var.min() > 0
    with pytest.raises(ValueError, match="unknown knob"):
        stream.set_knobs(threshold=1.0)


def test_track_rows_and_their_covariance(tmp_path):
    rec = load_recording(PYSHOE)
    prep = prepare(rec, named_setup("real-fixed"))
    block = run_prepared(prep)
    run = run_prepared(prep, track=True)
    np.testing.assert_allclose(run.pos, block.pos, atol=ROUNDING_M, rtol=0)
    np.testing.assert_array_equal(run.states[0, :, :3], run.pos[0])
    path = write_track_csv(run_states(run, float(rec.time[0])), tmp_path / "t.csv")
    assert path.read_text().splitlines()[0] == ",".join(TRACK_COLUMNS)
    data = np.loadtxt(path, delimiter=",", skiprows=1)
    assert data.shape == (prep.num_samples, len(TRACK_COLUMNS))
    np.testing.assert_allclose(data[:, 1:4], run.pos[0], atol=1e-8)
    np.testing.assert_allclose(np.diff(data[:, 0]), 1 / prep.rate_hz, atol=2e-6)  # %.6f
    # attitude: yaw, pitch, roll = state's 9th, 7th, 8th entries
    np.testing.assert_allclose(data[:, 7], run.states[0, :, 8], atol=1e-8)
    # the initial covariance during alignment, then positive variances
    np.testing.assert_allclose(data[: prep.n_align, 12], 1e-6)  # initial_position_std²
    assert (data[:, 12:] > 0).all()
    with pytest.raises(ValueError, match="track=True"):
        run_states(block, 0.0)


def test_stream_errors_and_short_streams():
    rec = load_recording(PYSHOE)
    stream = ZuptStream(200.0, "real-fixed")
    with pytest.raises(ValueError, match="must be"):
        stream.feed(np.zeros((3, 2)), np.zeros((3, 2)))
    bad = rec.f_b[:5].copy()
    bad[2, 0] = np.nan
    with pytest.raises(ValueError, match="stream sample 2"):
        stream.feed(rec.omega_b[:5], bad)
    short = ZuptStream(200.0, "real-fixed")
    assert len(short.feed(rec.omega_b[:100], rec.f_b[:100])) == 0
    with pytest.raises(ValueError, match="within the still start"):
        short.close()
    ok = ZuptStream(200.0, "real-fixed")
    # the decision needs the longest window (200) + 0.1 s: none after 210 samples,
    # which close() then aligns as a whole record would be
    out = ok.feed(rec.omega_b[:210], rec.f_b[:210])
    assert len(out) == 0 and not ok.aligned
    rest = ok.close()
    assert len(rest) == 210 and ok.aligned and rest.navigating.sum() == 10
    with pytest.raises(ValueError, match="before any sample"):
        ZuptStream(200.0).close()
