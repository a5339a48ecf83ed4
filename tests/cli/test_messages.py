"""Messages that answer what the user meant: suggestions within the right vocabulary
(a network's usual names, a variant's short name), the option or argument the user
typed, no value said twice, binary input recognised as such. Each is one line, exit 2."""

from __future__ import annotations

from pathlib import Path

import pytest

from tests.cli.test_report_cli import in_process


@pytest.mark.parametrize(
    ("args", "expected"),
    [
        (
            ("run", "s1", "--network", "adhoc"),
            "--network: unknown network 'adhoc' (did you mean 'ah'?)",
        ),
        (("run", "s1", "--network", "wifi"), "(did you mean 'wlan'?)"),
        (("run", "s1", "--network", "wlann"), "(did you mean 'wlan'?)"),
        (("run", "s1", "--behaviour", "leader-follower"), "(did you mean 'lf'?)"),
        (("check", "lff"), "'lff' is not a variant (did you mean 'lf'?); variants: behaviour.lf"),
        (("check", "xyzzy"), "'xyzzy' is not a variant; variants: behaviour.lf, behaviour.lf-wait"),
        (("radio", "show", "no-such-profile"), "PROFILE: unknown radio profile 'no-such-profile'"),
    ],
)
def test_suggestions_and_names(
    args: tuple[str, ...], expected: str, capsys: pytest.CaptureFixture[str],
    monkeypatch: pytest.MonkeyPatch,
) -> None:  # fmt: skip
    out = in_process(capsys, monkeypatch, *args)
    assert out.returncode == 2
    (line,) = out.stderr.strip().splitlines()
    assert expected in line, line


def test_a_bad_value_is_said_once(
    capsys: pytest.CaptureFixture[str], monkeypatch: pytest.MonkeyPatch
) -> None:
    out = in_process(capsys, monkeypatch, "run", "s1", "--behaviour", "lf", "--set",
                     "behaviour.utility=nope")  # fmt: skip
    assert out.returncode == 2
    assert out.stderr.count("'nope'") == 1, out.stderr
    assert "unknown utility 'nope'; choose from greedy, original, path" in out.stderr


@pytest.mark.parametrize("data", [bytes(range(256)), b"name: S1\x00\x01\x02"])
def test_a_binary_scenario_is_named_binary(
    data: bytes, tmp_path: Path, capsys: pytest.CaptureFixture[str],
    monkeypatch: pytest.MonkeyPatch,
) -> None:  # fmt: skip
    path = tmp_path / "scenario.yaml"
    path.write_bytes(data)
    out = in_process(capsys, monkeypatch, "run", str(path))
    assert out.returncode == 2
    assert "not YAML text (expected a UTF-8 YAML file)" in out.stderr
    assert "codec" not in out.stderr
