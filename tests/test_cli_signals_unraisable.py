"""A signal that lands where Python cannot raise (a weakref callback, ``__del__``) while a
command runs: no "Exception ignored" traceback is reported; other unraisable errors still
are, and the hook is restored when the command ends."""
import sys

from acid_cli._signals import InterruptGuard


class _Raises:
    def __init__(self, exc):
        self.exc = exc

    def __del__(self):
        raise self.exc


def test_an_interrupt_in_a_finaliser_is_not_reported(monkeypatch):
    seen = []
    monkeypatch.setattr(sys, "unraisablehook", lambda u: seen.append(type(u.exc_value)))
    before = sys.unraisablehook
    with InterruptGuard():
        _Raises(KeyboardInterrupt())   # collected at once: __del__ raises, Python ignores it
        _Raises(ValueError("kept"))
    assert seen == [ValueError]
    assert sys.unraisablehook is before
