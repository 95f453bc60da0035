"""An exception raised at an instruction CPython gives no line number (the jump
back of a nested loop, where pytest-timeout's SIGALRM landed in our CI) is
reported as the test's failure, not as a pytest INTERNALERROR
(``harness/tracebacks.py``). The exception is raised there deterministically
from a trace function with opcode events."""

import pytest

RAISER = '''
import dis
import sys


def loop(xs, ys):
    n = 0
    for x in xs:
        if x:
            for y in ys:
                if y:
                    n += 1
    return n


LINELESS = {i.offset for i in dis.get_instructions(loop) if i.positions.lineno is None}


class Interrupted(Exception):
    pass


def raise_where_no_line():
    """Run ``loop`` and raise at its first instruction without a line number."""
    def tracer(frame, event, arg):
        if frame.f_code is loop.__code__:
            frame.f_trace_opcodes = True
            if event == "opcode" and frame.f_lasti in LINELESS:
                raise Interrupted("timeout")
        return tracer
    sys.settrace(tracer)
    try:
        loop([1, 1], [1, 1])
    finally:
        sys.settrace(None)
'''


@pytest.fixture
def raiser(tmp_path, monkeypatch):
    (tmp_path / "lineless.py").write_text(RAISER)
    monkeypatch.syspath_prepend(str(tmp_path))
    import lineless
    if not lineless.LINELESS:
        pytest.skip("this Python gives every instruction of the loop a line number")
    yield lineless
    import sys
    sys.modules.pop("lineless", None)


def test_repair_gives_every_entry_a_line(raiser):
    from pytest_flockai.harness.tracebacks import repair
    with pytest.raises(raiser.Interrupted) as info:
        raiser.raise_where_no_line()
    exc = info.value

    def lines(e):
        out, tb = [], e.__traceback__
        while tb is not None:
            out.append((tb.tb_frame.f_code.co_name, tb.tb_lineno))
            tb = tb.tb_next
        return out

    before = lines(exc)
    assert ("loop", None) in before                     # what CPython gave
    after = lines(repair(exc))
    assert [n for n, _ in after] == [n for n, _ in before]
    assert all(line is not None for _, line in after)
    code = raiser.loop.__code__
    loop_line = dict(after)["loop"]
    assert code.co_firstlineno < loop_line <= code.co_firstlineno + 6
    # entries that had a line keep it
    assert [x for x in after if x[0] != "loop"] == [x for x in before if x[0] != "loop"]


def test_a_test_interrupted_where_no_line_is_reported_as_failed(pytester):
    pytester.makepyfile(lineless=RAISER)
    pytester.makepyfile(test_it='''
import lineless

def test_interrupted():
    lineless.raise_where_no_line()
''')
    res = pytester.runpytest_inprocess("-p", "no:cacheprovider")
    out = res.stdout.str()
    assert "INTERNALERROR" not in out
    res.assert_outcomes(failed=1)
    assert "Interrupted: timeout" in out
