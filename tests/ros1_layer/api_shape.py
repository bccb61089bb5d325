"""Print the public API shape of ROS 1 Python modules as JSON: for each module, each public
name with its kind and, for callables, its parameter names and kinds (a class: __init__'s).

Run by tests/test_ros1_layer.py twice, under Debian's real ROS 1 and under orchestra's layer,
so the two can be compared name by name (argv: module names)."""
import importlib
import inspect
import json
import sys


def params(obj):
    target = obj.__init__ if inspect.isclass(obj) else obj
    try:
        sig = inspect.signature(target)
    except (TypeError, ValueError):
        return None
    names = [(p.name, p.kind.name) for p in sig.parameters.values()]
    if inspect.isclass(obj) and names and names[0][0] == "self":
        names = names[1:]
    return names


def shape(module_name, names):
    module = importlib.import_module(module_name)
    out = {}
    for name in names:
        obj = getattr(module, name, None)
        if obj is None:
            out[name] = None
            continue
        kind = "class" if inspect.isclass(obj) else "callable" if callable(obj) else "value"
        entry = {"kind": kind}
        if kind != "value":
            entry["params"] = params(obj)
        if kind == "class":
            entry["methods"] = {m: params(getattr(obj, m)) for m in dir(obj)
                                if not m.startswith("_") and callable(getattr(obj, m, None))}
        out[name] = entry
    return out


if __name__ == "__main__":
    request = json.loads(sys.argv[1])  # {module: [names]}
    print(json.dumps({m: shape(m, names) for m, names in request.items()}))
