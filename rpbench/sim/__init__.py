"""The batch-round simulator: the round loop (:mod:`.simulator`), vehicle plans and
positions (:mod:`.fleet`) and the solver-independent tie-breaking among optima (:mod:`.ties`)."""

from rpbench.sim.simulator import SimResult, Simulator

__all__ = ["SimResult", "Simulator"]
