"""Ctrl-C stops a long render: the render polls Python's signals while it runs (the GIL
released), stops at the next row of pixels and raises KeyboardInterrupt."""

import _thread
import signal
import threading
import time

import pytest

import kalos

# About 4e9 samples: hours of work, so an early end can only be the interrupt.
LONG = dict(spp=60000, res=(256, 256), threads=1, method="plain")


def interrupt_by_signal():
    signal.pthread_kill(threading.main_thread().ident, signal.SIGINT)


@pytest.mark.parametrize("send", [_thread.interrupt_main, interrupt_by_signal], ids=["interrupt_main", "SIGINT"])
def test_ctrl_c_stops_a_long_render(send):
    # A shell starts a background job (`cmd &`, nohup) with SIGINT ignored; Python then
    # keeps it ignored. Give the test Python's own handler, as an interactive session has.
    if signal.getsignal(signal.SIGINT) is signal.SIG_IGN:
        signal.signal(signal.SIGINT, signal.default_int_handler)
    assert signal.getsignal(signal.SIGINT) is signal.default_int_handler
    scene = kalos.load("cornell")
    seen = []
    timer = threading.Timer(0.5, send)
    t0 = time.monotonic()
    timer.start()
    try:
        with pytest.raises(KeyboardInterrupt):
            kalos.render(scene, progress=lambda done, total: seen.append((done, total)), **LONG)
    finally:
        timer.cancel()
    # ended by the interrupt (a generous bound: the render itself would take hours)
    assert time.monotonic() - t0 < 60
    # the progress callback saw the render run
    assert seen and seen[-1][1] == 60000 * 256 * 256
    # and the module still renders afterwards
    assert kalos.render(scene, spp=1, res=(8, 8)).shape == (8, 8, 3)


def test_an_exception_in_the_progress_callback_stops_the_render():
    def cb(done, total):
        raise RuntimeError("stop here")

    with pytest.raises(RuntimeError, match="stop here"):
        kalos.render("cornell", progress=cb, **LONG)


def test_the_gil_is_released_while_rendering():
    """Another Python thread runs while a render is in progress."""
    ticks = []
    stop = threading.Event()

    def count():
        while not stop.is_set():
            ticks.append(1)
            time.sleep(0.001)

    t = threading.Thread(target=count)
    t.start()
    try:
        before = len(ticks)
        kalos.render("cornell", spp=64, res=(128, 128), threads=1, method="plain")
        during = len(ticks) - before
    finally:
        stop.set()
        t.join()
    assert during > 10, during
