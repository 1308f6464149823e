"""The ``preform`` command's entry point (its console script and ``python -m preform``).

The garbage collector is paused before anything else is imported (``preform.collector``): the
command's start-up, importing click, pydantic and preform's modules, is then never collected.
``preform.cli`` resumes it before a command computes."""

from preform.collector import pause_for_startup


def main() -> None:
    """Run the ``preform`` command line (``preform.cli.main``)."""
    pause_for_startup()
    from preform.cli import main as cli_main

    cli_main()


if __name__ == "__main__":
    main()
