"""bench/broad_loo: the leave-one-trial-out choice and its two rules, on hand-made score tables
(the BROAD run itself is `invoke bench --only broad_loo`)."""

from __future__ import annotations

import numpy as np

from bench.broad_loo import WORST_WEIGHT, distribution, leave_one_out, objective


def test_each_trial_is_scored_with_the_point_chosen_on_the_others() -> None:
    # point 0 is best on trials 0 and 1, point 1 on trial 2 by far: leaving trial 2 out
    # chooses point 0 (the others' mean), leaving 0 or 1 out keeps trial 2's pull in the mean
    tot = np.array([[1.0, 1.0, 5.0],
                    [1.5, 1.5, 1.0]])
    vqf = np.ones(3)
    held, chosen = leave_one_out(tot, vqf, "mean")
    # without trial 0: means 3.0 (point 0) vs 1.25 (point 1) -> 1; the same without trial 1;
    # without trial 2: 1.0 vs 1.5 -> 0
    assert chosen == [1, 1, 0]
    assert held.tolist() == [1.5, 1.5, 5.0]


def test_the_worst_aware_rule_trades_mean_for_the_worst_ratio() -> None:
    # point 1 loses 0.02° of mean and cuts the worst ratio to VQF from 3 to 2.5: with
    # WORST_WEIGHT 0.05° per unit that is worth 0.025°, so the worst-aware rule takes it
    tot = np.array([[1.0, 1.0, 3.0, 1.0],
                    [1.04, 1.04, 2.5, 1.5]])
    vqf = np.ones(4)
    assert objective(tot[0], tot[0] / vqf, "mean") < objective(tot[1], tot[1] / vqf, "mean")
    gap = objective(tot[0], tot[0] / vqf, "worst-aware") - objective(tot[1], tot[1] / vqf, "worst-aware")
    assert np.isclose(gap, -(tot[1].mean() - tot[0].mean()) + WORST_WEIGHT * 0.5)
    assert gap > 0


def test_distribution_counts_the_trials_above_one_and_a_half() -> None:
    assert distribution(np.array([0.5, 1.0, 1.6, 2.0])) == "0.50 / 1.30 / 2.00, 2 above 1.5×"
