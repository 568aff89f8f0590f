"""Where the model and measured fibers disagree, which effect explains it, and the gap left.

Modules (data flow order):

- :mod:`.observables`: the registry of observables (one entry per measured
  quantity: kind, unit, range and NaN rule, noise law, scoring scale, how it
  is read from a run) that every module below iterates;
- :mod:`.schema`: measured-fiber table (documented schema), validating loader, writer;
- :mod:`.noise`: measurement model (start and outcome noise);
- :mod:`.synth`: measured-like data from the model with hidden effects;
- :mod:`.simulate`, :mod:`.copies`: batches of runs on a persistent pool; jittered
  copies with common random numbers;
- :mod:`.scores`, :mod:`.stats`, :mod:`.gap`: leave-one-out scores, permutation
  tests against the noise floor, Holm, bootstrap; the gap per observable;
- :mod:`.localise`: where the gap lives (shallow tree, binned maps);
- :mod:`.library`, :mod:`.fit`: fittable effects, signature ranking, 1D fits;
- :mod:`.decide`: out-of-sample decision (named / ambiguous / unexplained / none);
- :mod:`.workflow`: :func:`run_discrepancy`, the whole procedure within a budget;
- :mod:`.report`: Markdown, figures, JSON summary, updated config.
"""
