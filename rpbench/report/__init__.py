"""Renderers: every document a results folder is shown as, drawn from its files alone.

:mod:`.comparison` writes a comparison folder's ``report.md`` (its tables; the paper's Table 2 layout);
:mod:`.plots` its figures; :mod:`.tables` the LaTeX and CSV copies; :mod:`.combine` several folders of one
scenario as one comparison; :mod:`.evaluation` and :mod:`.leaderboard` an evaluation's report and
statistics; :mod:`.bench` a solver benchmark's summary; :mod:`.html` the web page of every kind of folder.
Renderers read the folder formats (:mod:`rpbench.results`) and never the checker; the checker may
re-render a document to compare it with the one in a folder.
"""
