"""Helpers for the qdemsph verification cases: run the solver, run FEniCSx references,
read outputs. Imported by verification/conftest.py and the cases' test files."""


def must(fn, *args, **kwargs):
    """Call fn; turn the harness's own errors (solver or reference script failed, with their
    message) into a clean test failure instead of a traceback chain."""
    import pytest

    from .fenicsx import FenicsxError
    from .qdemsph import QdemsphError

    try:
        return fn(*args, **kwargs)
    except (QdemsphError, FenicsxError, KeyError) as e:
        msg = str(e)
    pytest.fail(msg, pytrace=False)
