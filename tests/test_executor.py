"""treesketch.executor without Ray: in-process and process-pool runs, errors, options."""

from __future__ import annotations

import os

import pytest

from treesketch.executor import (
    ExecutorError,
    InlineExecutor,
    LocalExecutor,
    from_options,
    make_executor,
    run_ordered,
)


class Square:
    """A worker factory: the worker remembers the pid that built it (warm state)."""

    def __call__(self):
        built_in = os.getpid()

        def one(x: int) -> tuple[int, int]:
            if x == 3:
                raise ValueError("three is bad")
            return x * x, built_in

        return one


class BrokenSetup:
    def __call__(self):
        raise RuntimeError("no model here")


@pytest.mark.parametrize("executor", [InlineExecutor(), LocalExecutor(1), LocalExecutor(2)])
def test_values_in_order_and_errors_reported(executor):
    seen = []
    outs = run_ordered(executor, Square(), list(range(7)), on_outcome=seen.append)
    assert [o.index for o in outs] == list(range(7)) and len(seen) == 7
    assert [o.value[0] for o in outs if o.ok] == [0, 1, 4, 16, 25, 36]
    bad = outs[3]
    assert not bad.ok and bad.value is None and bad.error.startswith("ValueError: three is bad")
    for o in outs:
        if o.ok:  # the worker ran in the process that built it: built once, kept warm
            assert o.value[1] == o.worker
    if executor.workers == 1:
        assert {o.worker for o in outs} == {os.getpid()}
    else:
        assert os.getpid() not in {o.worker for o in outs}


@pytest.mark.parametrize("executor", [InlineExecutor(), LocalExecutor(2)])
def test_a_worker_that_cannot_start_fails_every_piece_plainly(executor):
    outs = run_ordered(executor, BrokenSetup(), [1, 2, 3])
    assert all(not o.ok and "no model here" in o.error for o in outs)


def test_no_pieces():
    assert run_ordered(LocalExecutor(2), Square(), []) == []


@pytest.mark.parametrize(
    ("call", "match"),
    [
        (lambda: LocalExecutor(0), "workers"),
        (lambda: LocalExecutor(True), "workers"),
        (lambda: make_executor("dask"), "unknown executor 'dask'"),
        (lambda: make_executor("local", address="1.2.3.4:6379"), "--address"),
        (lambda: from_options("ray", workers=2, address="auto"), "--workers"),
    ],
)
def test_bad_options_are_named(call, match):
    with pytest.raises(ExecutorError, match=match):
        call()


def test_from_options_local():
    assert from_options("local") is None  # one process: the caller runs in-process
    ex = from_options("LOCAL", workers=3)
    assert isinstance(ex, LocalExecutor) and ex.workers == 3


def test_parameters_pickle_for_worker_processes():
    import pickle

    from weberpenn import species

    p = species.sample("palm", seed=1)
    q = pickle.loads(pickle.dumps(p))
    assert q == p and type(q) is type(p) and q.to_dict() == p.to_dict()


@pytest.mark.parametrize(
    ("address", "match"), [("127.0.0.1:1", "no Ray cluster answers"), ("nowhere", "HOST:PORT")]
)
def test_an_unreachable_cluster_fails_fast(address, match):
    pytest.importorskip("ray")
    from treesketch.executor import RayExecutor

    with pytest.raises(ExecutorError, match=match):
        RayExecutor(address=address)


def test_tsn_estimate_does_not_depend_on_the_callers_torch_threads():
    """Ray gives its workers one thread, this process has all cores: the estimate must
    be the same values either way."""
    import torch

    from render.sketch import SketchRenderer
    from treesketch.estimators import TSNEstimator
    from weberpenn import build_mesh, grow, species

    est = TSNEstimator.load()
    img = SketchRenderer(build_mesh(grow(species.sample("palm", seed=1)))).sketch(30.0, 256)
    before = torch.get_num_threads()
    try:
        torch.set_num_threads(1)
        one = est.estimate(img).params.to_dict()
        torch.set_num_threads(2)
        two = est.estimate(img).params.to_dict()
        assert torch.get_num_threads() == 2  # the caller's setting is left as it was
    finally:
        torch.set_num_threads(before)
    assert one == two
