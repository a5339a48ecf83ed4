"""Variants as specs: the registry, parameters, ``--set`` and ``mrcomm variants``."""

from __future__ import annotations

import json
import subprocess
import sys
from typing import Any

import pytest
from pydantic import BaseModel, ConfigDict, Field

from mrcomm.errors import InputError
from mrcomm.run.config import make_config, param_assignments
from mrcomm.sim.mission import run_mission
from mrcomm.specs import REGISTRY, SpecRegistry, VariantSpec, get_spec
from tests.conftest import S1_PATH


def mrcomm(*args: str) -> subprocess.CompletedProcess[str]:
    code = "from mrcomm.cli.main import app; app()"
    return subprocess.run(
        [sys.executable, "-c", code, *args], capture_output=True, text=True, timeout=300
    )


BUILT_IN = frozenset(
    {
        "behaviour.nb",
        "behaviour.lf",
        "threshold.none",
        "threshold.slt",
        "threshold.ssd",
        "threshold.esd",
        "network.wlan",
        "network.ah",
        "utility.original",
        "utility.greedy",
        "utility.path",
    }
)


def test_built_in_variants_are_found_through_entry_points() -> None:
    origins = {s.key: s.origin for s in REGISTRY.all()}
    assert set(origins) >= BUILT_IN
    assert {origins[key] for key in BUILT_IN} == {"mrcomm"}


def test_a_second_spec_under_the_same_name_is_refused() -> None:
    registry = SpecRegistry(group="mrcomm.no-such-group")
    spec = VariantSpec(kind="utility", name="u", entry=len)
    registry.register(spec)
    registry.register(spec)  # the same spec again is harmless
    with pytest.raises(ValueError, match="registered twice"):
        registry.register(VariantSpec(kind="utility", name="u", entry=abs, origin="other"))


def test_unknown_names_and_parameters_are_one_line_errors() -> None:
    with pytest.raises(InputError, match=r"unknown behaviour 'lff' \(did you mean 'lf'\?\)"):
        get_spec("behaviour", "lff")
    with pytest.raises(InputError) as err:
        make_config(None, scenario=S1_PATH, behaviour="lf", params={"behaviour": {"utilty": 1}})
    assert "behaviour.utilty" in err.value.one_line()
    assert "did you mean 'utility'" in err.value.one_line()
    with pytest.raises(InputError, match=r"behaviour\.utility"):
        make_config(None, scenario=S1_PATH, behaviour="lf", params={"behaviour": {"utility": "x"}})
    with pytest.raises(InputError, match=r"network\.range_m"):
        make_config(None, scenario=S1_PATH, network="ah", params={"network": {"range_m": -1}})


def test_wrong_combinations_come_from_the_specs() -> None:
    with pytest.raises(InputError, match="threshold 'ssd' needs network 'ah'"):
        make_config(None, scenario=S1_PATH, network="wlan", threshold="ssd")


def test_only_non_default_parameters_are_kept_and_legacy_options_fold_in() -> None:
    config = make_config(
        None,
        scenario=S1_PATH,
        network="ah",
        threshold="slt",
        behaviour="lf",
        slt_warning=3.0,
        params={"behaviour": {"utility": "original", "follow_distance": 1.0}},
    )
    assert config.params == {
        "threshold": {"warning_m": 3.0},
        "behaviour": {"follow_distance": 1.0},
    }
    assert config.variant_params("threshold").warning_m == 3.0
    assert sorted(param_assignments(config)) == [
        "behaviour.follow_distance=1.0",
        "threshold.warning_m=3.0",
    ]
    assert config.variants() == {"network": "ah-v1", "behaviour": "lf-v1", "threshold": "slt-v1"}
    # A default set explicitly is the same configuration as one not set.
    plain = make_config(None, scenario=S1_PATH, behaviour="lf", params={"behaviour": {}})
    explicit = make_config(
        None, scenario=S1_PATH, behaviour="lf", params={"behaviour": {"utility": "original"}}
    )
    assert plain == explicit


def test_a_section_named_after_a_variant_applies_to_that_variant_only() -> None:
    """``threshold.esd.warning_dbm``: ESD runs get it, SLT runs of the same study do not
    (and stay the configuration they were); a typo in it is an error in any run."""
    scoped = {"threshold": {"esd": {"warning_dbm": -70.0}, "slt": {"warning_m": 3.0}}}
    esd = make_config(None, scenario=S1_PATH, network="radio", threshold="esd", params=scoped)
    slt = make_config(None, scenario=S1_PATH, network="radio", threshold="slt", params=scoped)
    assert esd.params == {"threshold": {"warning_dbm": -70.0}}
    assert slt.params == {"threshold": {"warning_m": 3.0}}
    ssd = make_config(None, scenario=S1_PATH, network="radio", threshold="ssd", params=scoped)
    assert ssd == make_config(None, scenario=S1_PATH, network="radio", threshold="ssd")
    with pytest.raises(InputError, match="warning_dbn"):
        make_config(
            None,
            scenario=S1_PATH,
            threshold="slt",
            network="ah",
            params={"threshold": {"esd": {"warning_dbn": -70.0}}},
        )


def test_parameters_reach_the_variants(s1_resources: Any) -> None:
    """The AH range and the SLT warning distance set as parameters change the run."""
    base = {"scenario": S1_PATH, "network": "ah", "threshold": "slt", "seed": 3, "max_time": 120}
    default = run_mission(make_config(None, **base), s1_resources)
    wide = run_mission(
        make_config(None, **base, params={"network": {"range_m": 100.0}}), s1_resources
    )
    assert default.messages["pose"]["dropped_range"] > 0
    assert wide.messages["pose"]["dropped_range"] == 0


@pytest.mark.slow
def test_set_greedy_utility_changes_lf_results() -> None:
    common = [
        "run", str(S1_PATH), "--network", "ah", "--threshold", "slt", "--behaviour", "lf",
        "--seed", "2", "--json",
    ]  # fmt: skip
    original = mrcomm(*common)
    greedy = mrcomm(*common, "--set", "behaviour.utility=greedy")
    assert original.returncode == 0 and greedy.returncode == 0, greedy.stderr
    a, b = json.loads(original.stdout), json.loads(greedy.stdout)
    assert b["config"]["params"] == {"behaviour": {"utility": "greedy"}}
    a.pop("wall_time_s"), b.pop("wall_time_s")
    a.pop("config"), b.pop("config")
    assert a != b  # a different leader is chosen: the run differs


@pytest.mark.parametrize(
    ("args", "expected"),
    [
        (["--set", "behaviour.utilty=greedy"], "--set behaviour.utilty: unknown parameter"),
        (["--set", "behaviour.utility=fast"], "--set behaviour.utility: unknown utility 'fast'"),
        (["--set", "behavior.utility=greedy"], "did you mean 'behaviour'"),
        (["--set", "behaviour.utility"], "expected KIND.KEY=VALUE"),
        (["--set", "network.range_m=-3"], "--set network.range_m: "),
        (["--set", "network.range_m=nan"], "--set network.range_m: "),
        (["--behaviour", "lff"], "--behaviour: unknown behaviour 'lff' (did you mean 'lf'?)"),
        (["--network", "adhoc"], "--network: unknown network 'adhoc'"),
        (["--threshold", "ssd"], "needs network 'ah'"),
    ],
)
def test_bad_set_is_one_line_exit_2(args: list[str], expected: str) -> None:
    done = mrcomm("run", str(S1_PATH), "--behaviour", "lf", "--network", "ah", *args)
    if "--network" in args and "adhoc" in args:
        done = mrcomm("run", str(S1_PATH), *args)
    if "--threshold" in args:
        done = mrcomm("run", str(S1_PATH), "--network", "wlan", *args)
    assert done.returncode == 2, done.stderr
    lines = done.stderr.strip().splitlines()
    assert len(lines) == 1 and "Traceback" not in done.stderr
    assert expected in lines[0], lines[0]


def test_variants_lists_parameters_with_defaults_and_units() -> None:
    done = mrcomm("variants", "--json")
    assert done.returncode == 0, done.stderr
    rows = {f"{r['kind']}.{r['name']}": r for r in json.loads(done.stdout)}
    ah = {p["key"]: p for p in rows["network.ah"]["parameters"]}
    assert ah["network.range_m"]["default"] == 8.0 and ah["network.range_m"]["unit"] == "m"
    lf = {p["key"]: p for p in rows["behaviour.lf"]["parameters"]}
    assert lf["behaviour.utility"]["default"] == "original"
    assert "behaviour.collision.danger_radius" in lf  # nested parameters, dotted
    assert rows["threshold.ssd"]["network_types"] == ["ah", "radio"]
    assert rows["behaviour.lf"]["uses_aon"] is True
    text = mrcomm("variants", "threshold")
    assert text.returncode == 0 and "threshold.warning_dbm" in text.stdout
    assert "behaviour" not in text.stdout


class _Params(BaseModel):
    model_config = ConfigDict(frozen=True, extra="forbid")
    k: int = Field(1, ge=0)


def test_a_spec_validates_its_parameters_into_its_model() -> None:
    spec = VariantSpec(kind="utility", name="t", entry=len, params=_Params)
    assert spec.make_params({"k": 3}) == _Params(k=3)
    with pytest.raises(InputError, match=r"utility\.k"):
        spec.make_params({"k": -1})
    with pytest.raises(InputError, match="it has k"):
        spec.make_params({"j": 1})


def test_sweep_set_adds_fixed_parameters_and_refuses_a_factor(tmp_path: Any) -> None:
    from mrcomm.experiment.schema import load_experiment

    schema = tmp_path / "s.yaml"
    schema.write_text(
        f"scenario: {S1_PATH}\nrepetitions: 1\nfactors: {{behaviour: [lf], network: [ah]}}\n"
    )
    plain = load_experiment(schema)
    greedy = load_experiment(schema, {"behaviour": {"utility": "greedy"}})
    assert greedy.configurations[0].config.params == {"behaviour": {"utility": "greedy"}}
    assert greedy.configurations[0].config_id != plain.configurations[0].config_id
    schema.write_text(schema.read_text() + "params: {network.range_m: 9}\n")
    with pytest.raises(InputError, match=r"network\.range_m is already set"):
        load_experiment(schema, {"network": {"range_m": 10}})
    schema.write_text(
        f"scenario: {S1_PATH}\nrepetitions: 1\n"
        "factors: {behaviour: [lf], behaviour.utility: [original, greedy]}\n"
    )
    with pytest.raises(InputError, match=r"behaviour\.utility is already set"):
        load_experiment(schema, {"behaviour": {"utility": "greedy"}})


def test_a_new_variant_version_is_a_new_configuration(
    tmp_path: Any, monkeypatch: pytest.MonkeyPatch
) -> None:
    from dataclasses import replace

    from mrcomm.experiment.schema import load_experiment

    schema = tmp_path / "s.yaml"
    schema.write_text(f"scenario: {S1_PATH}\nrepetitions: 1\nfactors: {{behaviour: [nb]}}\n")
    before = load_experiment(schema).configurations[0]
    bumped = replace(get_spec("behaviour", "nb"), version=2)
    monkeypatch.setitem(REGISTRY._specs["behaviour"], "nb", bumped)
    after = load_experiment(schema).configurations[0]
    assert after.config.variants()["behaviour"] == "nb-v2"
    assert after.config_id != before.config_id and after.label == before.label


def test_the_report_lists_each_configurations_parameters_and_versions() -> None:
    import pandas as pd

    from mrcomm.analysis.report_provenance import config_rows

    options = {"params": {"behaviour": {"utility": "greedy", "collision": {"danger_radius": 1.2}}}}
    options["variants"] = {"behaviour": "lf-v1"}
    frame = pd.DataFrame([{"config_id": "c", "label": "L", "options": json.dumps(options)}])
    row = config_rows(frame)[0]
    assert row[:2] == ["c", "L"]
    assert row[2] == "behaviour.collision.danger_radius=1.2, behaviour.utility=greedy"
    assert row[3] == "behaviour lf-v1"


def test_a_variant_for_simulation_only_is_refused_in_live_mode() -> None:
    from mrcomm.net.network import AdHoc

    spec = VariantSpec(
        kind="network",
        name="simonly",
        entry=AdHoc,
        params=get_spec("network", "ah").params,
        modes=frozenset({"sim"}),
    )
    with REGISTRY.registered(spec):
        config = make_config(None, scenario=S1_PATH, network="simonly")
        config.check_mode("sim")
        with pytest.raises(InputError) as err:
            config.check_mode("live")
    assert (
        err.value.one_line()
        == "--network: network 'simonly' runs in sim mode only, not in live mode"
    )
    # The radio runs in both modes.
    make_config(None, scenario=S1_PATH, network="radio").check_mode("live")
