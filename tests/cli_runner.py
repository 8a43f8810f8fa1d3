"""Run the ``nfdepth`` command in-process and capture what it printed (test helper)."""

from nfdepth.cli import main


def run_cli(capture, *argv):
    """``main(argv)`` (each argument as a string) with pytest's ``capsys`` or ``capfd``: ``(exit code, stdout, stderr)``."""
    code = main([str(a) for a in argv])
    out, err = capture.readouterr()
    return code, out, err
