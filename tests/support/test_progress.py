"""Progress bars: drawn on a terminal, silent in pipelines."""

import io

from trajcomp.support.progress import Stages, is_terminal, progress


class Terminal(io.StringIO):
    """A text stream that says it is a terminal."""

    def isatty(self):
        return True


def test_a_terminal_shows_the_count_and_the_rate():
    stream = Terminal()
    with progress(1000, desc="compensate", unit="target", stream=stream, delay=0) as bar:
        bar.update(400)
        bar.update(600)
    final = stream.getvalue().split("\r")[-1]
    assert final.startswith("compensate: 100%")
    assert "1000/1000" in final and "target/s" in final


def test_a_pipeline_gets_nothing():
    stream = io.StringIO()
    with progress(10, desc="compensate", stream=stream, delay=0) as bar:
        bar.update(10)
    assert stream.getvalue() == ""


def test_a_short_run_on_a_terminal_draws_nothing():
    stream = Terminal()
    with progress(10, desc="compensate", stream=stream, delay=60) as bar:
        bar.update(10)
    assert stream.getvalue() == ""


def test_closed_or_plain_objects_are_no_terminal():
    closed = io.StringIO()
    closed.close()
    assert not is_terminal(closed)
    assert not is_terminal(object())
    assert is_terminal(Terminal())


def test_stages_name_the_running_stage_and_count_every_one():
    stream = Terminal()
    seen = []
    with Stages(("read", "compensate", "write"), desc="weld.csv", stream=stream, delay=0) as stages:
        for _ in range(3):
            seen.append(stages.bar.desc)
            stages.advance()
    assert seen == ["weld.csv: read", "weld.csv: compensate", "weld.csv: write"]
    final = stream.getvalue().split("\r")[-1]
    assert final.startswith("weld.csv: write: 100%") and "3/3" in final


def test_disabled_stages_draw_nothing_even_on_a_terminal():
    stream = Terminal()
    with Stages(("read", "write"), desc="weld.csv", stream=stream, delay=0, enabled=False) as stages:
        stages.advance()
        stages.advance()
    assert stream.getvalue() == ""
