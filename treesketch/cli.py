"""The ``treesketch`` command line.  Each command group lives in its own module
(``cli_grow``, ``cli_dataset``, ``cli_train``, ``cli_predict``, ``cli_eval``, ``cli_serve``)
and registers itself here; heavy imports (torch, mitsuba) happen inside the commands so
``treesketch --help`` stays fast."""

from __future__ import annotations

import typer

from . import cli_dataset, cli_eval, cli_grow, cli_predict, cli_serve, cli_train

app = typer.Typer(
    name="treesketch",
    help="Turn a sketch of a tree into a 3D Weber-Penn (Blender Sapling) tree.",
    no_args_is_help=True,
    add_completion=False,
    pretty_exceptions_enable=False,
)

for _module in (cli_grow, cli_dataset, cli_train, cli_predict, cli_eval, cli_serve):
    _module.register(app)


def main() -> None:  # pragma: no cover - console entry point
    app()


if __name__ == "__main__":  # pragma: no cover
    main()
