"""A learning dispatcher on rpbench/Dispatch-v0: a linear scoring rule trained by the cross-entropy method.

Each edge's score (metres) is a weighted sum of its features; a passenger's wait edge is worth a learnt
constant.  MB is one point of this family (weights -1 on pick-up km, +1 on saving km, waiting never worth
it).  The cross-entropy method samples weight vectors around a mean, keeps the best quarter by episode
return (the total saving, km) on the training seeds, and moves the mean to them.  The learnt rule is then
graded on held-out seeds (and, with --test-scenario, on another scenario): each episode a results folder
beside NP, MB and FL, Hindsight and the upper bound, checked by rpbench's checker.

    pip install 'rpbench[env]'
    python examples/gym/cem.py --out cem-runs
    python examples/gym/cem.py --out cem-runs --test-scenario haikou-peak --test-sample 0.3

Only numpy: the point is the environment, not the learner.  Exit status 1 if a graded episode fails the
checker.
"""

from __future__ import annotations

import argparse
import sys
from pathlib import Path

import numpy as np

import rpbench.env
from rpbench.env.observation import EDGE_FEATURES

# The features a score weighs (km and minutes, as observed), and the wait edge's constant last.
WEIGHED = ("pickup_km", "saving_km", "first_dropped", "remaining_km", "solo_km", "waited_min")
COLUMNS = [EDGE_FEATURES.index(f) for f in WEIGHED]
WAIT = EDGE_FEATURES.index("wait")
MB_WEIGHTS = np.array([-1.0, 1.0, 0.0, 0.0, 0.0, 0.0, -1000.0])
#: The first spread of each weight around MB's.
SPREAD = np.array([1.0, 1.0, 1.0, 0.5, 0.5, 0.5, 1000.0])
BESIDE = ("np", "mb", "fl")


def scores(obs: dict, weights: np.ndarray) -> np.ndarray:
    """One score per edge row, in metres: the weighted features, or the wait constant for a wait edge."""
    features = obs["edges"][:, COLUMNS].astype(float)
    return 1000.0 * np.where(obs["edges"][:, WAIT] == 1, weights[-1], features @ weights[:-1])


def episode(env, weights: np.ndarray, seed: int) -> tuple[float, dict]:
    obs, _ = env.reset(seed=seed)
    total = 0.0
    while True:
        obs, reward, terminated, _, info = env.step(scores(obs, weights))
        total += reward
        if terminated:
            return total, info


def train(args: argparse.Namespace) -> np.ndarray:
    """The cross-entropy method's mean weights after ``args.iterations`` iterations."""
    rng = np.random.default_rng(args.seed)
    seeds = [int(s) for s in args.train_seeds.split(",")]
    env = rpbench.env.DispatchEnv(scenario=args.scenario, sample=args.sample)
    mean, spread = MB_WEIGHTS.copy(), SPREAD.copy()
    elite_n = max(2, args.population // 4)
    for it in range(args.iterations):
        population = mean + spread * rng.standard_normal((args.population, len(mean)))
        returns = np.array([np.mean([episode(env, w, s)[0] for s in seeds]) for w in population])
        elite = population[np.argsort(returns)[-elite_n:]]
        # a floor on the spread keeps the search from collapsing onto one point too early
        mean, spread = elite.mean(axis=0), elite.std(axis=0) + 0.05 * SPREAD
        print(f"iteration {it + 1}: mean return {returns.mean():7.1f} km, best {returns.max():7.1f} km (train seeds)")
    env.close()
    return mean


def grade(weights: np.ndarray, scenario: str, sample: float, seeds: list[int], out: Path) -> list[str]:
    """The learnt rule on each seed beside NP, MB and FL; prints the savings and the bracket."""
    env = rpbench.env.DispatchEnv(
        scenario=scenario, sample=sample, results_dir=out, name="cem", label="CEM (linear)", beside=BESIDE
    )
    print(f"{scenario} at {sample:.0%}, held-out seeds: total saving (km)")
    print(f"  {'seed':>4} {'CEM':>8} {'NP':>8} {'MB':>8} {'FL':>8}   [LB, U]            CEM's ratio in   checker")
    verdicts = []
    for seed in seeds:
        _, info = episode(env, weights, seed)
        by_run = info["saving_km_by_run"]
        verdicts.append(info["check"])
        print(
            f"  {seed:>4} {by_run['cem']:8.1f} {by_run['np']:8.1f} {by_run['mb']:8.1f} {by_run['fl']:8.1f}   "
            f"[{info['best_known_km']:.1f}, {info['upper_bound_km']:.1f}]   "
            f"[{info['competitive_ratio_bound']:.3f}, {info['competitive_ratio_best_known']:.3f}]   {info['check']}"
        )
    env.close()
    return verdicts


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--scenario", default="toy", help="where the rule learns (default toy)")
    parser.add_argument("--sample", type=float, default=0.5)
    parser.add_argument("--iterations", type=int, default=6)
    parser.add_argument("--population", type=int, default=12)
    parser.add_argument("--train-seeds", default="1,2")
    parser.add_argument("--test-seeds", default="0,3,4", help="held-out seeds, graded")
    parser.add_argument("--test-scenario", help="also grade the learnt rule here (e.g. haikou-peak), seed 0")
    parser.add_argument("--test-sample", type=float, default=0.3)
    parser.add_argument("--seed", type=int, default=0, help="the learner's own random seed")
    parser.add_argument("--out", default="cem-runs", help="a new folder for the graded episodes")
    args = parser.parse_args()
    out = Path(args.out)
    if out.exists():
        sys.exit(f"--out {args.out!r} already exists; give a new folder")
    weights = train(args)
    print("learnt weights:", dict(zip([*WEIGHED, "wait"], np.round(weights, 3).tolist(), strict=True)))
    tests = [int(s) for s in args.test_seeds.split(",")]
    verdicts = grade(weights, args.scenario, args.sample, tests, out / args.scenario)
    if args.test_scenario:
        verdicts += grade(weights, args.test_scenario, args.test_sample, [0], out / args.test_scenario)
    print(f"graded episodes: {out}/")
    if any(v != "OK" for v in verdicts):
        sys.exit(f"a graded episode failed the checker: {verdicts}")


if __name__ == "__main__":
    main()
