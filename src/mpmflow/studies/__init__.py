"""Studies beside the runs: ``paper`` (the paper's study, `mpmflow study paper`: the dam
breaks of its Figs. 2-4 with both schemes) with ``paper_figures``, and ``reference_data``
(the measured and reference series in ../shared/data and the error measures against
them, which the validation report also uses). The validation report itself is the
``validation`` package (`mpmflow validate`), kept at the top: it is the project's
acceptance suite, which the tests and benchmarks import by that name."""
