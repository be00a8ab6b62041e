"""The offline oracles (paper Eqs. 16-20, docs/algorithms.md §4): candidate pairs
(:mod:`.pairs`) and the maximum-weight matching over them (:mod:`.solve`)."""

from rpbench.oracle.pairs import CandidatePairs, PairRules, find_candidates
from rpbench.oracle.solve import OracleResult, solve_oracle

__all__ = ["CandidatePairs", "OracleResult", "PairRules", "find_candidates", "solve_oracle"]
