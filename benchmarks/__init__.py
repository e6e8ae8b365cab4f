"""The benchmark scripts (``python benchmarks/NAME.py``, the job service's in
``benchmarks/service/``; see README.md), the helpers they share in ``benchmarks/lib/``
(``results_md``, ``sapling_run``, ``serve_process``, ``shape_v1``) and parts of
``bench_refine`` and ``compare_sapling``.  A package of the project, so the probes, the
documentation pictures' scripts and the tests import those helpers as ``benchmarks.lib.NAME``
however they were started."""
