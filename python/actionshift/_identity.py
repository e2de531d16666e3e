"""Identity by content of the Python code that enters a job (docs/methods.md, "Identity").

A Python policy or method enters a job's id by what it is, not by what it is called: the SHA-256 of
its code (bytecode, constants, default arguments, closure values and the user-defined globals it
refers to, recursively), of the values that configure it, and of the files it names. Code from
installed libraries (numpy, the standard library) is identified by module and name. A value with no
stable content (an open file, a handle to a GPU model) cannot be identified: the caller is told to
name it with a version and its files instead.
"""
import hashlib as _hashlib
import json as _json
import os as _os
import re as _re
import sys as _sys
import sysconfig as _sysconfig
import types as _types

import numpy as _np


class UnstableIdentity(ValueError):
    """The object refers to something whose content cannot be hashed; `where` says what."""

    def __init__(self, where, value):
        self.where = where
        super().__init__(f"{where} is a {type(value).__name__}, which has no stable content identity")


def _library_roots():
    roots = set()
    for key in ("stdlib", "platstdlib", "purelib", "platlib"):
        path = _sysconfig.get_paths().get(key)
        if path:
            roots.add(_os.path.realpath(path))
    for prefix in (_sys.prefix, _sys.base_prefix, _sys.exec_prefix):
        roots.add(_os.path.realpath(_os.path.join(prefix, "lib")))
    return tuple(sorted(roots))


_LIBRARY_ROOTS = _library_roots()
_OWN_DIR = _os.path.dirname(_os.path.realpath(__file__))


def _is_library_module(name):
    """True for a module of the standard library, an installed package or actionshift itself. Python
    code whose module is `builtins` or `__main__` (made by exec(), typed at a prompt) is user code."""
    if name in ("builtins", "__main__", None, ""):
        return False
    if name in _sys.builtin_module_names:
        return True
    mod = _sys.modules.get(name)
    path = getattr(mod, "__file__", None)
    if not path:
        return name != "__main__" and mod is not None
    path = _os.path.realpath(path)
    return path.startswith(_LIBRARY_ROOTS) or path.startswith(_OWN_DIR)


class _Hasher:
    def __init__(self):
        self.h = _hashlib.sha256()
        self.active = set()

    def put(self, tag, data=b""):
        if isinstance(data, str):
            data = data.encode("utf-8", "surrogatepass")
        self.h.update(tag.encode() + b":" + str(len(data)).encode() + b":" + data)

    def feed(self, v, where, depth=0):
        if depth > 200:
            raise UnstableIdentity(where, v)
        if v is None or isinstance(v, (bool, int, float, complex, str, bytes)):
            self.put("v", repr((type(v).__name__, v)))
            return
        if isinstance(v, _np.ndarray):
            if v.dtype == object:
                raise UnstableIdentity(where, v)
            self.put("nd", f"{v.dtype.str}{v.shape}")
            self.put("nd-bytes", _np.ascontiguousarray(v).tobytes())
            return
        if isinstance(v, _np.generic):
            self.put("np", repr((v.dtype.str, v.item())))
            return
        if isinstance(v, _np.random.Generator):  # a seeded generator is its state
            self.put("np-generator", type(v.bit_generator).__name__)
            self.feed(v.bit_generator.state, f"{where}.bit_generator.state", depth + 1)
            return
        if isinstance(v, _np.random.RandomState):
            self.put("np-randomstate")
            self.feed(list(v.get_state()), f"{where}.get_state()", depth + 1)
            return
        if isinstance(v, _types.ModuleType):
            self.put("module", v.__name__ + "@" + str(getattr(v, "__version__", "")))
            return
        if isinstance(v, (_types.BuiltinFunctionType, _types.BuiltinMethodType, _np.ufunc)):
            self.put("builtin", f"{getattr(v, '__module__', '')}.{getattr(v, '__qualname__', getattr(v, '__name__', ''))}")
            return
        key = id(v)
        if key in self.active:  # a cycle (a recursive function, a class naming itself)
            self.put("cycle", getattr(v, "__qualname__", type(v).__name__))
            return
        self.active.add(key)
        try:
            self._feed_object(v, where, depth)
        finally:
            self.active.discard(key)

    def _feed_object(self, v, where, depth):
        if isinstance(v, (list, tuple, set, frozenset)):
            items = sorted(v, key=repr) if isinstance(v, (set, frozenset)) else v
            self.put("seq", type(v).__name__ + str(len(items)))
            for i, x in enumerate(items):
                self.feed(x, f"{where}[{i}]", depth + 1)
            return
        if isinstance(v, dict):
            self.put("dict", str(len(v)))
            for k in sorted(v, key=repr):
                self.feed(k, where, depth + 1)
                self.feed(v[k], f"{where}[{k!r}]", depth + 1)
            return
        if isinstance(v, _types.CodeType):
            self.put("code", v.co_name)
            self.put("co_code", v.co_code)
            self.put("co_names", ",".join(v.co_names))
            self.put("co_varnames", ",".join(v.co_varnames))
            for i, c in enumerate(v.co_consts):
                self.feed(c, f"{where}.<const {i}>", depth + 1)
            return
        if isinstance(v, _types.MethodType):
            self.feed(v.__func__, where, depth + 1)
            self.feed(v.__self__, f"{where}.__self__", depth + 1)
            return
        if isinstance(v, _types.FunctionType):
            self._feed_function(v, where, depth)
            return
        if isinstance(v, type):
            self._feed_class(v, where, depth)
            return
        if isinstance(v, (staticmethod, classmethod, property)):
            for part in ("__func__", "fget", "fset", "fdel"):
                f = getattr(v, part, None)
                if f is not None:
                    self.feed(f, where, depth + 1)
            return
        if hasattr(v, "__dict__"):
            self._feed_instance(v, where, depth)
            return
        raise UnstableIdentity(where, v)

    def _feed_instance(self, v, where, depth):
        self.feed(type(v), f"{where}.__class__", depth + 1)
        self.put("vars")
        for k in sorted(vars(v)):
            self.feed(k, where, depth + 1)
            self.feed(vars(v)[k], f"{where}.{k}", depth + 1)

    def _feed_class(self, cls, where, depth):
        module = getattr(cls, "__module__", "")
        self.put("class", f"{module}.{cls.__qualname__}")
        if not cls.__flags__ & (1 << 9) or _is_library_module(module):  # a C type (not a heap type), or a library's
            return
        for base in cls.__bases__:
            if base is not object:
                self.feed(base, f"{where}.__bases__", depth + 1)
        for k in sorted(cls.__dict__):
            v = cls.__dict__[k]
            code_like = isinstance(v, (_types.FunctionType, staticmethod, classmethod, property, type))
            # dunder data (__module__, __doc__, and caches such as the __slotnames__ copy.deepcopy adds) is not code
            if k in ("__dict__", "__weakref__") or (k.startswith("__") and k.endswith("__") and not code_like):
                continue
            self.feed(k, where, depth + 1)
            if code_like:
                self.feed(v, f"{cls.__qualname__}.{k}", depth + 1)
                continue
            # class-level data: its value when it has one that can be hashed; a class attribute that holds
            # run-time state (a list of objects, a lock) is not configuration and is named only
            try:
                sub = _Hasher()
                sub.feed(v, f"{cls.__qualname__}.{k}", depth + 1)
                self.put("class-data", sub.h.hexdigest())
            except UnstableIdentity:
                self.put("class-state", k)

    def _feed_function(self, f, where, depth):
        module = getattr(f, "__module__", "") or ""
        self.put("function", f"{module}.{f.__qualname__}")
        if _is_library_module(module):
            return
        self.feed(f.__code__, f"{f.__qualname__}", depth + 1)
        self.feed(f.__defaults__, f"{f.__qualname__}.__defaults__", depth + 1)
        self.feed(f.__kwdefaults__, f"{f.__qualname__}.__kwdefaults__", depth + 1)
        for name, cell in zip(f.__code__.co_freevars, f.__closure__ or ()):
            try:
                value = cell.cell_contents
            except ValueError:  # an empty cell
                value = None
            self.feed(name, where, depth + 1)
            self.feed(value, f"{f.__qualname__}: closure variable '{name}'", depth + 1)
        for name in sorted(_global_names(f.__code__)):
            if name in f.__globals__:
                self.feed(name, where, depth + 1)
                self.feed(f.__globals__[name], f"{f.__qualname__}: global '{name}'", depth + 1)


def _global_names(code):
    names = set(code.co_names)
    for c in code.co_consts:
        if isinstance(c, _types.CodeType):
            names |= _global_names(c)
    return names


def content_sha256(obj, where):
    """SHA-256 (hex) of `obj`'s code and values; raises UnstableIdentity naming what has none."""
    h = _Hasher()
    h.feed(obj, where)
    return h.h.hexdigest()


def files_sha256(files, what):
    """The content of a list of files as `actionshift run --policy-files` hashes it (names and order do
    not matter), or "" for no files; absolute paths, for the job spec's record."""
    if files is None:
        return "", []
    if isinstance(files, (str, bytes, _os.PathLike)):
        files = [files]
    paths, digests = [], []
    for f in files:
        path = _os.path.abspath(_os.fspath(f))
        if not _os.path.isfile(path):
            raise ValueError(f"{what}: {path}: not a regular file")
        h = _hashlib.sha256()
        with open(path, "rb") as fh:
            for chunk in iter(lambda: fh.read(1 << 20), b""):
                h.update(chunk)
        paths.append(path)
        digests.append(h.hexdigest())
    if not paths:
        return "", []
    return _hashlib.sha256(_json.dumps(sorted(digests), separators=(",", ":")).encode()).hexdigest(), paths


def snake_name(name):
    s = _re.sub(r"(?<=[a-z0-9])([A-Z])", r"_\1", name).lower()
    return _re.sub(r"[^a-z0-9_.-]", "_", s).strip("_") or "method"


def policy_identity(policy, name, version=None, files=None):
    """The backbone sha256 of a Python policy: its name, declared version, code and files."""
    files_hash, paths = files_sha256(files, "policy_files")
    if version is None:
        try:
            code = content_sha256(policy, name)
        except UnstableIdentity as e:
            raise ValueError(
                f"evaluate: policy: cannot identify {name} by its content ({e}); pass policy_version='...' "
                f"(and policy_files=[...] for its weights) to name it") from None
    else:
        if not isinstance(version, str) or not version:
            raise TypeError("evaluate: policy_version: expected a non-empty str")
        code = ""
    doc = {"code_sha256": code, "files_sha256": files_hash, "name": name, "version": version or ""}
    return _hashlib.sha256(_json.dumps(doc, sort_keys=True, separators=(",", ":")).encode()).hexdigest(), paths


_RUNGS = ("pool", "grammar", "none")


def method_identity(method):
    """What a Python method object declares and is: name, version, rung, params and content hash."""
    cls = type(method)
    name = getattr(method, "name", None) or snake_name(cls.__name__)
    if not isinstance(name, str) or not _re.fullmatch(r"[a-z][a-z0-9_.-]{0,63}", name):
        raise ValueError(f"evaluate: method.name: expected a name of [a-z0-9_.-] starting with a letter (got {name!r})")
    version = getattr(method, "version", "0")
    if not isinstance(version, str) or not version:
        raise TypeError(f"evaluate: method {name}: version: expected a non-empty str (got {version!r})")
    rung = getattr(method, "rung", "none")
    if rung == "oracle":
        raise ValueError(f"evaluate: method {name}: rung: the oracle rung is reserved for the built-in oracle "
                         f"(declare 'pool', 'grammar' or 'none')")
    if rung not in _RUNGS:
        raise ValueError(f"evaluate: method {name}: rung: expected 'pool', 'grammar' or 'none' (got {rung!r})")
    for needed in ("begin_episode", "encode"):
        if not callable(getattr(method, needed, None)):
            raise TypeError(f"evaluate: method {name}: needs {needed}(); a method object has begin_episode(seed), "
                            f"encode(canonical, R) and observe(raw, response, R)")
    declared = getattr(method, "params", None)
    if declared is not None and not isinstance(declared, dict):
        raise TypeError(f"evaluate: method {name}: params: expected a dict of the values that configure it")
    params = dict(declared or {})
    try:
        params_text = _json.dumps(params, sort_keys=True, allow_nan=False)
    except (TypeError, ValueError) as e:
        raise ValueError(f"evaluate: method {name}: params: must be JSON values ({e})") from None
    # the class's code; without declared params, every attribute the object holds configures it
    try:
        h = _Hasher()
        h.feed(cls, cls.__qualname__)
        if declared is None:
            for k in sorted(vars(method)) if hasattr(method, "__dict__") else ():
                h.feed(k, name)
                h.feed(vars(method)[k], f"{cls.__qualname__}.{k}")
        code = h.h.hexdigest()
    except UnstableIdentity as e:
        raise ValueError(f"evaluate: method {name}: cannot identify it by its content ({e}); declare `params` "
                         f"(a dict of the values that configure it) and give it a `version`") from None
    _, paths = files_sha256(getattr(method, "files", None), f"method {name}: files")  # hashed by the registry
    return {"name": name, "version": version, "rung": rung, "params": params_text, "code_sha256": code, "files": paths}
