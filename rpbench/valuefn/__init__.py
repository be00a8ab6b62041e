"""A learned value of a vehicle's state, V(cell, time bin), for value-function dispatch (``vf``).

The family of Xu et al. (KDD 2018, "Large-scale order dispatch in on-demand ride-hailing platforms: a
learning and planning approach"): a tabular value of where and when a vehicle is vacant is learned by
policy evaluation from trajectories rpbench simulates itself, and the dispatcher adds the discounted
value change of each option to its matching weight (:mod:`rpbench.strategies.value`).

The modules, in the order a model is made: :mod:`.cells` (the grid of cells and the time bins),
:mod:`.transitions` (a run's vehicle transitions and their rewards), :mod:`.learn` (policy evaluation:
the exact batch solution or online TD(0)), :mod:`.model` (the artefact: arrays, a JSON description and
their digest) and :mod:`.train` (the training runs on training days only, and the cache).
The method and its equations: docs/value-function.md.
"""

from rpbench.valuefn.cells import Grid
from rpbench.valuefn.learn import LEARN_METHODS, evaluate_policy
from rpbench.valuefn.model import ValueModel, load_model
from rpbench.valuefn.transitions import Transitions, transitions_of_run

__all__ = ["LEARN_METHODS", "Grid", "Transitions", "ValueModel", "evaluate_policy", "load_model", "transitions_of_run"]
