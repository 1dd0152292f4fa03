"""Design scenario documents shared by the design kind's scenario and report tests."""

#: the hub-boom co-design as a ``design`` document: wall t against the LQ cost, first frequency
#: and structural mass bounded, SLSQP compared with trust-constr
HUB_BOOM = {
    "kind": "design",
    "name": "hub-boom co-design",
    "problem": "hub_boom_codesign",
    "variables": {"t": {"start": "2 mm", "lower": "0.5 mm", "upper": "3 mm"}},
    "objective": "lq_cost",
    "constraints": [
        {"response": "frequency_hz", "min": "6 Hz"},
        {"response": "mass", "max": "300 g"},
    ],
    "optimizer": {"method": "slsqp", "compare": "trust-constr"},
}
