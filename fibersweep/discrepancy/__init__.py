"""Where the model and measured fibers disagree, which effect explains it, and the gap left.

Modules, by concept:

- candidates: :mod:`.candidates` (what may be named: the library effects with
  their search ranges), :mod:`.declared` (candidates from any setting);
- observables: :mod:`.observables` (what an observable is, and the registry
  that every other module iterates; the track observables' values come from
  :mod:`fibersweep.analysis.observables`), :mod:`.components` (observables as
  components on their scoring scale);
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
- what it cannot see: :mod:`.detection` (detection from expected z-vectors:
  limits, fibers to detect), :mod:`.power` (the power analysis by simulation,
  look-alikes);
- follow-up: :mod:`.followup` (the question a verdict leaves, and the
  follow-ups that run), :mod:`.next_measure` (what to measure next),
  :mod:`.discriminant` (the follow-up test of A against B: statistic, null,
  fibers to settle), :mod:`.settle` (follow-up fibers put to that test),
  :mod:`.advice` (what to try);
- the workflow: :mod:`.stages` (the stages over a frozen state),
  :mod:`.workflow` (:func:`~.workflow.run_discrepancy`, every stage within a
  budget), :mod:`.result` (what a run found: everything the report receives);
- report (formats and writes, computes nothing): :mod:`.report` (JSON summary,
  updated configs, all files), :mod:`.report_text` (Markdown of the analysis),
  :mod:`.report_followup` (Markdown of the follow-ups), :mod:`.report_format`
  (numbers in the Markdown), :mod:`.report_figures` (figures).

No module imports another that imports it, directly or not
(``tests/unit/test_discrepancy_imports.py``).
"""
