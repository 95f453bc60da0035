"""The package's import layers, bottom to top: each top-level module or subpackage of
``pytest_flockai`` imports only from its own layer or the layers below it (same-layer
imports between two names are each a decision, listed in tests/project/test_architecture.py).

Data only: tests/project/test_architecture.py and tests/project/test_layout.py enforce it, and the docs'
architecture page prints it (docs/gen.py). A new top-level name must be placed here.
"""

#: bottom to top; a name is a top-level module or subpackage of pytest_flockai
LAYERS: tuple[frozenset[str], ...] = (
    # 0: the vocabulary every layer shares: errors, units, clocks, checks, results
    frozenset({"errors", "physics", "phases", "clock", "_check", "_io", "kpis", "recording",
               "result", "limits", "memo", "_mujoco", "notebook", "_xp", "_deprecation",
               "_layers"}),
    # 1: what the drone carries and flies over: computers (latency) and worlds
    frozenset({"compute", "world"}),
    # 2: energy and sensors
    frozenset({"energy", "sensors"}),
    # 3: the radio link and the airframe (the MuJoCo model)
    frozenset({"comm", "airframe"}),
    # 4: control, the ML tasks and the probes
    frozenset({"control", "ml", "probes"}),
    # 5: the mission (one run path), its cache, fleets and policies
    frozenset({"mission", "cache", "fleet", "policy"}),
    # 6: a real MAVLink app flying the mission
    frozenset({"app"}),
    # 7: what the user drives: budgets, reports, sweeps, the CLI and the pytest plugin
    frozenset({"budgets", "report", "strategies", "plots", "cli", "__main__", "hookspecs",
               "harness", "reports", "plugin", "__init__", "sweeps"}),
)

__all__ = ["LAYERS"]
