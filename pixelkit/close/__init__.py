"""Design closure: ``pixelkit close DESIGN --out REVB.toml`` moves the knobs of the design's
``[close]`` table until every ``[spec]`` passes at every condition of the ``[verify]`` grid
(with its Monte Carlo yield), optimising the objective; see docs/close.md.

- the ``[close]`` table itself (schema, checks against the design's keys) is ``verify.close_table``,
  below the design loader;
- ``knobs``: the knob space (scaled coordinates, the values as written, designs at a point);
- ``margins``: each spec's margin at each condition, normalised, and the binding conditions;
- ``step``: the casadi subproblem on the linear models (trust region, conflicts);
- ``run``: one close, the loop (sensitivities, candidates re-verified by ``verify``, the yield);
- ``revision``: ``close_design``: a close per combination of circuit choices, the best, the files;
- ``output``: the terminal text, ``close.json``, the written revision.
"""
