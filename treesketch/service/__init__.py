"""The job service: ``create_app(ServiceConfig(data=...))`` -> a FastAPI app.

- ``POST /jobs`` (multipart: ``sketch`` file; fields ``refine``, ``budget``,
  ``time_limit``, ``height``, ``estimator``, ``species``) -> 202 with the job's id and
  links; 503 with ``Retry-After`` when the queue is full.  Several drawings of one tree:
  a ``sketch`` part and a ``yaw`` field (degrees from the first drawing, ``?``: not known)
  per drawing, at most ``treesketch.views.MAX_VIEWS``; the result's ``views`` and each
  later drawing's ``view2_before.png``, ``view2_after.png``, ...
- ``GET /jobs/{id}``: state (queued, running, done, failed, cancelled, expired), place in
  the queue, progress, and when done the result; ``GET /jobs/{id}/events``: the same as
  Server-Sent Events until the job finishes; ``DELETE /jobs/{id}``: cancel.
- ``GET /jobs/{id}/tree.glb`` (and ``tree.json``, ``tree_sapling.py``, ``compare.png``,
  ``sketch_before.png``, ``sketch_after.png``); 410 once expired.
- ``GET /jobs?limit=``, ``GET /health``, ``GET /status``; ``POST /predict`` submits and
  waits (and cancels if the client leaves); ``GET /`` is the drawing page.
- The interactive loop (``interactive``): ``GET /controls``, ``POST /trees`` (a tree
  grown from parameters and a person's controls, as a light GLB or JSON), a running job's
  current best tree at ``GET /jobs/{id}/preview/tree.glb`` (and ``sketch.png``; the
  job's progress says which ``preview`` is there), ``GET /examples``; ``tree_view.glb``
  is a finished job's light tree for the viewer (``tree.glb`` keeps full detail);
  ``GET /jobs/{id}/outline.png?turn=&size=``: a finished tree's sketch from another side.
- ``outlines``: ``GET /jobs/{id}/outlines.png?view=N``: a done job's drawing's outline
  (red) over its tree's (blue) at that drawing's view, as the CLI's ``--outlines``.

Jobs live in SQLite (WAL) under the data folder with their artefacts; on restart, jobs
that were running are marked failed and queued ones run.  Modules: ``store`` (the
database), ``pool`` and ``worker`` (local processes), ``ray_pool`` and ``actor`` (the same
workers as Ray actors, ``ServiceConfig(executor="ray", address=...)``), ``runner`` (the
pipeline run), ``limits`` (checks before work), ``guards`` (the Host, Origin and token
checks), ``owner`` (one server per data folder), ``app`` (routes), ``inprocess`` (the app
served from a thread of this process, for tests and scripts).
"""

from .app import ServiceConfig, create_app
from .limits import Limits
from .runner import ARTEFACTS, VIEW_ARTEFACTS, JobOptions
from .store import JobStore

__all__ = [
    "ARTEFACTS",
    "VIEW_ARTEFACTS",
    "JobOptions",
    "JobStore",
    "Limits",
    "ServiceConfig",
    "create_app",
]
