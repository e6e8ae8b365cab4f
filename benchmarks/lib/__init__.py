"""What the benchmark scripts share (none of it a script): ``results_md`` writes a
benchmark's section of RESULTS.md, ``sapling_run`` runs and records Blender's Sapling
(its record of every species, ``sapling_species_stats.json``, lies beside it),
``serve_process`` runs ``treesketch serve`` for the service benchmarks, ``shape_v1`` is the
shape distance before issue 12 (``bench_distance.py``'s reference column)."""
