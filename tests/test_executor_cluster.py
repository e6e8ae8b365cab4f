"""treesketch.executor on a two-node Ray cluster on this machine (Ray's test cluster):
pieces run on both nodes, and when one node is killed mid-run its pieces are retried on
the other and the run completes."""

from __future__ import annotations

import os
import sys
import time
from pathlib import Path

import pytest

pytest.importorskip("ray", reason="the cluster extra (pip install .[cluster])")

from treesketch.executor import RayExecutor  # noqa: E402

pytestmark = pytest.mark.slow


class Nap:
    """Pieces that take a moment, so both nodes get some while the run is going."""

    def __call__(self):
        def one(x: int) -> int:
            time.sleep(0.5)
            return x + 100

        return one


def test_two_nodes_and_a_node_killed_mid_run(monkeypatch):
    import ray
    from ray.cluster_utils import Cluster

    # the nodes' workers import this module, as a real cluster's nodes import treesketch
    here = str(Path(__file__).resolve().parent)
    root = str(Path(__file__).resolve().parents[1])
    monkeypatch.setenv("PYTHONPATH", os.pathsep.join([root, here, *sys.path[1:]]))
    cluster = Cluster(
        initialize_head=True, head_node_args={"num_cpus": 1, "include_dashboard": False}
    )
    try:
        second = cluster.add_node(num_cpus=1)
        cluster.wait_for_nodes()
        ex = RayExecutor(address=cluster.address)
        try:
            assert len(ex.nodes()) == 2 and ex.workers == 2
            window = 2 * ex.workers  # RayExecutor.run's pieces in flight, set at its start
            head_id = cluster.head_node.node_id
            second_id = second.node_id
            outs, killed_after = [], None
            for o in ex.run(Nap(), list(range(14))):
                outs.append(o)
                on_second = sum(1 for x in outs if x.node == second_id)
                if killed_after is None and on_second >= 2:
                    cluster.remove_node(second, allow_graceful=False)
                    killed_after = len(outs)
            assert killed_after is not None and killed_after < 14
            assert sorted(o.index for o in outs) == list(range(14))
            assert all(o.ok for o in outs), [o.error for o in outs if not o.ok]
            assert sorted(o.value for o in outs) == list(range(100, 114))
            nodes = {o.node for o in outs}
            assert nodes == {head_id, second_id}  # ran on both ...
            # ... then one: pieces the second node finished before it died may still come
            # back after the kill (their small results already reached the driver), but only
            # those in flight then, at most the run's window less the one just seen
            assert all(o.node == head_id for o in outs[killed_after + window - 1 :])
            assert sum(o.node == second_id for o in outs[killed_after:]) <= window - 1
        finally:
            ex.close()
    finally:
        ray.shutdown()
        cluster.shutdown()


def test_killed_ray_build_resumes_without_duplicates(tmp_path):
    """`kill -9` of a `--executor ray` build after its first tree; the rerun skips the
    finished trees and the manifest has every sketch once (workers never write: the
    killed driver leaves nothing half-written behind)."""
    import json

    from build_helpers import kill_and_resume_build

    out = tmp_path / "killed"
    kill_and_resume_build(out, ["--executor", "ray", "--workers", "2"], timeout=180)
    rows = [json.loads(x) for x in (out / "manifest.jsonl").read_text().splitlines()]
    keys = [(r["tree_id"], r["view"]) for r in rows]
    assert len(keys) == len(set(keys)) == 20
    assert not list(out.rglob("*.tmp"))
