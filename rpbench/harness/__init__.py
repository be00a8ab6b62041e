"""Experiments over scenarios: one comparison (:mod:`.comparison`), many days
(:mod:`.multiday`), parameter sweeps (:mod:`.sweep`) on parallel workers
(:mod:`.parallel`), and rendering or publishing any results folder
(:mod:`.render`, :mod:`.publish`)."""
