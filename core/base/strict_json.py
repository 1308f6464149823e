"""Strict JSON: every JSON preform writes has no NaN or infinity."""

from typing import Any


def clean_json(obj: Any) -> Any:
    """NaN/inf → None so that every JSON we write is strict JSON. (A case whose results hold a
    non-finite number is failed before its summary is written, so nothing is silently nulled.)"""
    if isinstance(obj, float):
        return obj if obj == obj and abs(obj) != float("inf") else None
    if isinstance(obj, dict):
        return {str(k): clean_json(v) for k, v in obj.items()}
    if isinstance(obj, list | tuple):
        return [clean_json(v) for v in obj]
    if hasattr(obj, "tolist"):
        return clean_json(obj.tolist())
    if hasattr(obj, "item"):
        return clean_json(obj.item())
    return obj
