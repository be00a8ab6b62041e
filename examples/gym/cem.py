"""A learning dispatcher on rpbench/Dispatch-v0: a linear scoring rule trained by the cross-entropy method.

Each edge's score (metres) is a weighted sum of its features; a passenger's wait edge is worth a learnt
constant.  MB is one point of this family (weights -1 on pick-up km, +1 on saving km, waiting never worth
it).  The cross-entropy method samples weight vectors around a mean, keeps the best quarter by episode
return (the total saving, km) on the training seeds, and moves the mean to them.  The learnt rule and MB
are then graded on a held-out seed: results folders checked by rpbench's checker, with the bracket.

    pip install 'rpbench[env]'
    python examples/gym/cem.py --scenario toy --sample 0.5 --iterations 6 --out cem-runs

Only numpy: the point is the environment, not the learner.
"""

from __future__ import annotations

import argparse
import sys

import numpy as np

import rpbench.env
from rpbench.env.observation import EDGE_FEATURES

# The features a score weighs (km and minutes, as observed), and the wait edge's constant last.
WEIGHED = ("pickup_km", "saving_km", "first_dropped", "remaining_km", "solo_km", "waited_min")
COLUMNS = [EDGE_FEATURES.index(f) for f in WEIGHED]
WAIT = EDGE_FEATURES.index("wait")
MB_WEIGHTS = np.array([-1.0, 1.0, 0.0, 0.0, 0.0, 0.0, -1000.0])


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


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--scenario", default="toy")
    parser.add_argument("--sample", type=float, default=0.5)
    parser.add_argument("--iterations", type=int, default=6)
    parser.add_argument("--population", type=int, default=12)
    parser.add_argument("--train-seeds", default="1,2")
    parser.add_argument("--test-seed", type=int, default=0)
    parser.add_argument("--seed", type=int, default=0, help="the learner's own random seed")
    parser.add_argument("--out", default="cem-runs", help="where the graded test episodes are written")
    args = parser.parse_args()
    rng = np.random.default_rng(args.seed)
    train = [int(s) for s in args.train_seeds.split(",")]
    env = rpbench.env.DispatchEnv(scenario=args.scenario, sample=args.sample)

    mean, spread = MB_WEIGHTS.copy(), np.array([1.0, 1.0, 1.0, 0.5, 0.5, 0.5, 1000.0])
    elite_n = max(2, args.population // 4)
    for it in range(args.iterations):
        population = mean + spread * rng.standard_normal((args.population, len(mean)))
        returns = np.array([np.mean([episode(env, w, s)[0] for s in train]) for w in population])
        elite = population[np.argsort(returns)[-elite_n:]]
        mean, spread = elite.mean(axis=0), elite.std(axis=0) + 0.05 * np.abs(MB_WEIGHTS) + 1e-3
        print(f"iteration {it + 1}: mean return {returns.mean():7.1f} km, best {returns.max():7.1f} km (train seeds)")
    env.close()

    graded = rpbench.env.DispatchEnv(scenario=args.scenario, sample=args.sample, results_dir=args.out)
    print(f"held-out seed {args.test_seed}:")
    verdicts = []
    for name, weights in (("MB", MB_WEIGHTS), ("CEM", mean)):
        saving, info = episode(graded, weights, args.test_seed)
        verdicts.append(info["check"])
        print(
            f"  {name:>3}: total saving {saving:7.1f} km, checker {info['check']}, bracket "
            f"[LB {info['best_known_km']:.1f}, U {info['upper_bound_km']:.1f}] km, "
            f"ratio in [{info['competitive_ratio_bound']:.3f}, {info['competitive_ratio_best_known']:.3f}] "
            f"({info['folder']})"
        )
    print("learnt weights:", dict(zip([*WEIGHED, "wait"], np.round(mean, 3).tolist(), strict=True)))
    graded.close()
    if any(v != "OK" for v in verdicts):
        sys.exit(f"a graded episode failed the checker: {verdicts}")


if __name__ == "__main__":
    main()
