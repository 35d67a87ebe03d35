"""In-process CLI runner for the sensor tests (no interpreter start-up per call)."""

def run_inprocess(capsys, *args):
    """The command line in this process (``pixelkit.cli.entry``): (exit status, stdout, stderr)."""
    from pixelkit.cli import entry
    try:
        entry([str(a) for a in args])
        code = 0
    except SystemExit as exc:
        code = exc.code
    cap = capsys.readouterr()
    return code, cap.out, cap.err
