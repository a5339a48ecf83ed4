"""Figure encoding: the same bytes in worker processes as in this process, and files
that do not change from one render to the next (a report rebuilt from the same database
is the same report)."""

from __future__ import annotations

from matplotlib.figure import Figure

from mrcomm.analysis.encoding import Encoder, encode, render


def _figure() -> Figure:
    fig = Figure(figsize=(4, 3), layout="constrained")
    ax = fig.subplots()
    ax.plot([0, 1, 2], [1, 3, 2], marker="o", label="a")
    ax.set_clip_on(True)
    ax.legend()
    ax.set_title("encoding")
    return fig


def test_each_format_renders_the_same_bytes_twice() -> None:
    for fmt in ("png", "svg", "pdf"):
        assert render(_figure(), fmt) == render(_figure(), fmt), fmt


def test_worker_processes_encode_exactly_what_this_process_does() -> None:
    here = encode(_figure(), vector=True)
    with Encoder(vector=True, jobs=2) as encoder:
        futures = [encoder.submit(_figure()) for _ in range(2)]
        there = [f.result() for f in futures]
    assert all(e == here for e in there)
    assert here.png.startswith(b"\x89PNG")
    assert here.svg is not None and b"<svg" in here.svg
    assert here.pdf is not None and here.pdf.startswith(b"%PDF")


def test_without_vector_only_png() -> None:
    with Encoder(vector=False, jobs=1) as encoder:
        encoded = encoder.submit(_figure()).result()
    assert encoded.svg is None and encoded.pdf is None and encoded.png
