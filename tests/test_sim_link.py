"""The whole chain with link errors: every sample through the C sender, the
channel simulator and the C receiver."""

from __future__ import annotations

import numpy as np

import attitude_c
from attitude_c.sim import AdcModel, SimConfig, simulate


def _cfg(**kw) -> SimConfig:
    base = {"duration": 60.0, "adc": AdcModel(backend="ideal"), "seed": 5}
    base.update(kw)
    return SimConfig(**base)


def test_clean_link_delivers_every_sample_unchanged() -> None:
    direct = simulate(_cfg(link="none"))
    linked = simulate(_cfg(link="c", ber=0.0))
    s = linked.summary["link"]
    assert s["sent"] == s["delivered"] == s["delivered_ok"] == 750
    assert s["lost"] == s["duplicated"] == s["corrupted_undetected"] == 0
    assert np.array_equal(direct.increments, linked.increments)
    assert np.array_equal(direct.q_est, linked.q_est)


def test_lossy_link_is_accounted_and_the_attitude_follows_what_was_delivered() -> None:
    """BER 5e-3 on both directions with 2 attempts per block: about a third of
    the exchanges (~100 bits) fail, so NAKs, timeouts, give-ups and some
    duplicates happen in 750 blocks."""
    direct = simulate(_cfg(link="none"))
    res = simulate(_cfg(link="c", ber=5e-3, link_attempts=2))
    s = res.summary["link"]
    assert s["sent"] == 750
    assert s["delivered"] == s["delivered_ok"] + s["duplicated"] + s["corrupted_undetected"]
    assert s["lost"] > 0 and s["delivered"] < 750
    assert s["delivered_ok"] + s["lost"] <= 750
    assert s["sender"]["naks"] + s["sender"]["timeouts"] > 0
    # every correctly delivered sample carries exactly the increment that was sent
    inc, idx = res.increments, res.sample_index
    assert len(inc) == s["delivered"]
    same = np.all(inc == direct.increments[idx], axis=1)
    assert np.count_nonzero(~same) == s["corrupted_undetected"]
    # the attitude is the integral of what was delivered, nothing else
    q0 = res.config.trajectory.quat(res.config.trajectory.t_start + idx[0] * res.config.period)
    n3 = len(inc) // 3 * 3
    q_ref = attitude_c.integrate(inc[:n3], method="rv3", q0=q0)
    assert np.array_equal(res.q_est, q_ref)
    # losses show up as error, and the summary reports them
    assert res.summary["errors_rad"]["attitude_angle"]["max_abs"] > \
        direct.summary["errors_rad"]["attitude_angle"]["max_abs"]
