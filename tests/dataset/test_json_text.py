"""to_json remembers the texts of plain dicts by value, type and sign: equal-looking values
of other types or signs still get their own text."""
import json

import numpy as np

from orbatt.dataset.build import to_json


def _reference(obj):
    return json.dumps(obj, sort_keys=True)


def test_remembered_texts_follow_types_and_signs():
    cases = [{"x": 0.0}, {"x": -0.0}, {"x": 1}, {"x": 1.0}, {"x": True}, {"x": None}, {"x": "1"},
             {"o": {"x": 0.0}}, {"o": {"x": -0.0}}, {"o": {"x": 1}}, {"o": {"x": True}}, {"x": float("nan")},
             {"b": 2.5, "a": "z"}, {"a": "z", "b": 2.5}]
    for _ in range(2):  # the second time from the remembered texts
        for c in cases:
            assert to_json(c) == _reference(c)


def test_other_values_encoded_as_before():
    assert to_json(None) == "{}"
    assert to_json({"a": np.float64(0.5), "b": np.arange(2)}) == '{"a": 0.5, "b": [0, 1]}'
    assert to_json({"a": [1, 2]}) == '{"a": [1, 2]}'
    assert to_json({1: "x"}) == '{"1": "x"}'
