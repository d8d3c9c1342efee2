"""One section of an estimation config file (config/estimation.yaml) as a parameter dataclass."""
from dataclasses import fields

from ..safe_yaml import load_yaml_file, short_repr


def load_section(path, name: str, cls):
    """`cls` (a dataclass with problems(prefix) -> list of messages) from the `name:` section of the
    YAML file at path; an absent section gives the defaults. A YAML integer given for a float field
    is that float (1 for 1.0). ValueError naming the file, each field and its value, for unknown keys
    and for every problem cls finds."""
    data = load_yaml_file(path)
    if data is None:
        data = {}
    if not isinstance(data, dict):
        raise ValueError(f"{path}: expected a mapping at the top, got {type(data).__name__}")
    section = data.get(name)
    if section is None:
        section = {}
    if not isinstance(section, dict):
        raise ValueError(f"{path}: {name}: expected a mapping, got {short_repr(section)}")
    types = {f.name: f.type for f in fields(cls)}
    problems = [f"{name}.{k}: unknown key (value {short_repr(v)})" for k, v in section.items() if k not in types]
    if not problems:
        values = {k: float(v) if types[k] is float and type(v) is int else v for k, v in section.items()}
        params = cls(**values)
        problems = params.problems(name)
    if problems:
        raise ValueError(f"{path}: " + "; ".join(problems))
    return params
