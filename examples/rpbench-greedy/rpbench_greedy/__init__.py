"""Example rpbench plug-ins: a strategy and a backend defined outside rpbench.

* :class:`~rpbench_greedy.strategy.GreedyPickup` — entry point ``greedy``
  of ``rpbench.strategies``;
* :class:`~rpbench_greedy.backend.DenseLSABackend` — entry point
  ``dense-lsa`` of ``rpbench.backends``, with the preset file :data:`PRESET`.

rpbench imports these modules only when a run names them, so this package
imports nothing heavy at import time either.
"""

from pathlib import Path

#: The solver preset of the dense-lsa backend: ``rpbench run --solver <this path>``.
PRESET = Path(__file__).with_name("dense-lsa.toml")
