"""Fixtures shared by test modules: the service tests' drawing (``sketch``), and the page
tests' (``tests/test_web*.py``) server, browser, page and finished jobs, whose helpers
are in ``web_helpers.py``.  A module may define its own fixture of the same name.

``make test`` runs the suite on two workers (pytest-xdist, ``-n 2 --dist loadfile``: each
module on one worker, so its module-scoped fixtures are made once and its tests run in
order; the session-scoped ones, once a worker, for the modules it runs); the modules that
start a Ray take turns (:func:`one_ray_at_a_time`).  A page test that only reads a
finished result shares one (``finished_job``); none may depend on the order its module's
tests run in."""

from __future__ import annotations

import fcntl
from collections.abc import Callable, Iterator
from typing import Any

import pytest

# the modules that start a Ray of their own (a local cluster, then killed): one at a time,
# whichever worker runs them (``make test`` runs two)
RAY_MODULES = {"test_executor_cluster.py", "test_executor_ray.py", "test_service_ray.py"}


@pytest.fixture(autouse=True, scope="module")
def one_ray_at_a_time(
    request: pytest.FixtureRequest, tmp_path_factory: pytest.TempPathFactory
) -> Iterator[None]:
    """A Ray module holds, while it runs, a lock every worker sees (beside the worker's
    temporary folder: under xdist, in the run's own); the other modules take none."""
    if request.path.name not in RAY_MODULES:
        yield
        return
    lock = tmp_path_factory.getbasetemp().parent / "ray-tests.lock"
    with lock.open("w") as f:
        fcntl.flock(f, fcntl.LOCK_EX)  # released when the file closes
        yield


@pytest.fixture(scope="session")
def sketch() -> bytes:
    """A palm drawn by the renderer, as PNG bytes: what the service tests submit."""
    from service_helpers import palm_sketch_png

    return palm_sketch_png()


@pytest.fixture(scope="session")
def server(tmp_path_factory: pytest.TempPathFactory) -> Iterator[str]:
    """A real server with one worker and the palm test estimator; its base URL.  One per
    test process (per xdist worker), for every page module that runs there: starting one
    (its worker process) took 2-5 s a module.  No page test depends on the server being
    its module's alone: a test counts jobs as a difference, and what the page keeps (the
    recent jobs, the pad) is in its own browser context.  A module may define its own
    (another estimator)."""
    from web_helpers import palm_service

    with palm_service(tmp_path_factory.mktemp("web")) as url:
        yield url


@pytest.fixture(scope="session")
def browser() -> Iterator[Any]:
    """Debian's chromium through Playwright, one per test process: each test takes a new
    context of it (``guarded_context``), which shares nothing with another's."""
    from web_helpers import chromium

    with chromium() as b:
        yield b


@pytest.fixture
def context(browser: Any, server: str) -> Iterator[Any]:
    """A new browser context on a desktop screen, held to the server (see
    ``guarded_context``): a test that opens a job by its link takes this, not ``page``
    (which first loads the empty drawing page)."""
    from web_helpers import DESKTOP, guarded_context

    with guarded_context(browser, server, **DESKTOP) as ctx:
        yield ctx


@pytest.fixture
def page(context: Any, server: str) -> Any:
    """The drawing page in ``context``."""
    from web_helpers import open_page

    return open_page(context, server)


@pytest.fixture(scope="session")
def finished_jobs() -> dict[tuple, str]:
    """The finished jobs made so far by ``finished_job``: (server, form fields) -> id."""
    return {}


@pytest.fixture(scope="module")
def finished_job(server: str, sketch: bytes, finished_jobs: dict[tuple, str]) -> Callable[..., str]:
    """``finished_job(**fields)``: the id of a finished job of the server made from
    ``sketch`` with the form ``fields`` (``budget`` 2 unless given), made the first time
    it is asked for and then shared by every test of the test process that asks for the
    same, for the page tests that only read a result (its view, its files, its
    candidates; an edit is a new tree, never a change to the job).  A test that makes a
    job in the page (the drawing, the submission, what follows) makes its own."""
    from service_helpers import finished_job_id

    def get(**fields: str) -> str:
        fields = {"budget": "2", **fields}
        key = (server, tuple(sorted(fields.items())))
        if key not in finished_jobs:
            finished_jobs[key] = finished_job_id(server, sketch, **fields)
        return finished_jobs[key]

    return get
