"""Where the model and measured fibers disagree, which effect explains it, and the gap left.

Modules, by concept:

- candidates: :mod:`.candidates` (what may be named: the library effects with
  their search ranges);
- observables: :mod:`.observables` (what an observable is, and the registry
  that every other module iterates), :mod:`.tracks` (the track observables of
  a measured or simulated track);
- measured data: :mod:`.schema` (the fibers table: schema, validation,
  writer), :mod:`.measured` (loading it with its trajectories);
- simulation of copies: :mod:`.simulate` (batches of runs on the sweep's
  executors), :mod:`.copies` (the measurement model and jittered copies with
  common random numbers), :mod:`.synth` (measured-like data with hidden effects);
- settings: :mod:`.settings` (the workflow's knobs and how a simulation budget
  is split);
- scores and statistics: :mod:`.scores` (fair scores, permutation tests, Holm,
  bootstrap);
- the gap: :mod:`.gap` (the tests per observable, its signature vector, the
  loss weights), :mod:`.localise` (where it lives), :mod:`.dispersion` (the
  dispersion and spread tests);
- fitting: :mod:`.signatures` (which candidates match the gap),
  :mod:`.estimate` (a fit's quoted value and interval), :mod:`.fit` (one
  effect: halves and pooled refit), :mod:`.pairs` (two effects: joint fit and
  forward selection);
- decision: :mod:`.decide` (out of sample: named, ambiguous, unexplained, none);
- follow-up: :mod:`.power` (detection limits, look-alikes), :mod:`.followup`
  (what to measure next, and when both run), :mod:`.settle` (fibers measured
  next test the verdict's two hypotheses), :mod:`.advice` (what to try);
- the workflow: :mod:`.workflow` (:func:`~.workflow.run_discrepancy`, every
  stage within a budget);
- report: :mod:`.report` (JSON summary, updated configs, all files),
  :mod:`.report_text` (Markdown), :mod:`.report_figures` (figures).

No module imports another that imports it, directly or not
(``tests/unit/test_discrepancy_imports.py``).
"""
