"""The worked host in Python (examples/python/plug_flow.py, issue 42): a plug-flow
reactor of six cells whose books balance exactly in every one of 16 reactors and whose
M0 and M1 per cell agree with core's sectional reference (Student t at 1e-7 per check,
docs/design/statistical-tests.md)."""

import importlib.util
import pathlib

EXAMPLE = pathlib.Path(__file__).resolve().parents[2] / "examples" / "python" / "plug_flow.py"


def test_the_plug_flow_host_balances_and_meets_the_sectional_reference(capsys):
    spec = importlib.util.spec_from_file_location("plug_flow", EXAMPLE)
    module = importlib.util.module_from_spec(spec)
    spec.loader.exec_module(module)
    assert module.main(2000.0)
    out = capsys.readouterr().out
    assert out.count("balanced exactly") == module.REPLICAS
    assert "NOT BALANCED" not in out and "OFF" not in out
