# The module's public surface (python/README.md, "Properties and methods"):
# every public member has a docstring, the named values of its enum-like
# strings are each explained, and renamed members keep working with a
# DeprecationWarning.
import inspect
import os
import re
import warnings

import pytest

import hamal

README = os.path.join(os.path.dirname(__file__), "..", "README.md")


def _own_text(name, doc):
    """The docstring without pybind11's signature lines: what a person wrote.
    For an overloaded function, the text of each overload."""
    lines = (doc or "").strip().splitlines()
    chunks, current = [], []
    for line in lines:
        if re.match(rf"^(\d+\. )?{re.escape(name)}\(", line.strip()):
            if current or chunks:
                chunks.append("\n".join(current).strip())
            current = []
        elif line.strip() != "Overloaded function.":
            current.append(line)
    chunks.append("\n".join(current).strip())
    if "Overloaded function." in (doc or ""):
        chunks = chunks[1:]  # the text before "1." is the overload list's header
    return chunks


def _undocumented(qualified, name, obj):
    if isinstance(obj, (staticmethod, classmethod)):
        obj = obj.__func__  # else the wrapper's generic text would pass for documentation
    if isinstance(obj, property):
        doc = obj.__doc__ or (obj.fget and obj.fget.__doc__)
    elif inspect.ismemberdescriptor(obj):
        doc = inspect.getdoc(obj)  # a slot's text in its class' __slots__ dict, as help() shows it
    else:
        doc = obj.__doc__
    if any(not text for text in _own_text(name, doc)):
        return [qualified]
    return []


def public_members(module):
    """(qualified name, name, object) of every public function, class, method,
    property and slot of `module`, as `dir` lists them."""
    for name in sorted(dir(module)):
        if name.startswith("_"):
            continue
        obj = getattr(module, name)
        if inspect.ismodule(obj):
            continue
        if inspect.isclass(obj):
            yield name, name, obj
            for member, value in vars(obj).items():
                if member.startswith("_"):
                    continue
                yield f"{name}.{member}", member, value
        elif callable(obj):
            yield name, name, obj


def test_every_public_member_has_a_docstring():
    modules = [(hamal, "hamal.")]
    try:
        import matplotlib
        matplotlib.use("Agg")
        modules.append((hamal.plot, "hamal.plot."))
    except ImportError:  # hamal.plot needs matplotlib; the rest of the module does not
        pass
    missing, count = [], 0
    for module, prefix in modules:
        for qualified, name, obj in public_members(module):
            if module is hamal.plot and getattr(obj, "__module__", "hamal.plot") != "hamal.plot":
                continue  # what plot imports (plt, Ellipse, ...) is not its own
            count += 1
            missing += [prefix + q for q in _undocumented(qualified, name, obj)]
    assert count > 150
    assert not missing, f"{len(missing)} of {count} public members have no docstring:\n" + "\n".join(missing)


def test_the_walk_finds_an_undocumented_member():
    class Sample:
        """documented"""

        def documented(self):
            """yes"""

        def bare(self):
            pass

        @property
        def bare_property(self):
            return 1

        @staticmethod
        def bare_static():
            pass

    found = [q for q, n, o in ((f"Sample.{m}", m, v) for m, v in vars(Sample).items() if not m.startswith("_"))
             for q in _undocumented(q, n, o)]
    assert found == ["Sample.bare", "Sample.bare_property", "Sample.bare_static"]
    # pybind11's signature line alone is no documentation, for each overload.
    assert _own_text("f", "f(a: int) -> int\n") == [""]
    assert _own_text("f", "f(*args)\nOverloaded function.\n\n1. f(a: int) -> int\n\nOne.\n\n2. f(b: str) -> int\n") \
        == ["One.", ""]


@pytest.mark.parametrize("values, member", [
    (hamal.STATUS_CODES, hamal.Status.code),
    (hamal.UPDATE_KINDS, hamal.UpdateResult.kind),
])
def test_every_enum_value_is_explained_where_it_is_read(values, member):
    assert len(values) >= 3
    for value in values:
        assert f"'{value}'" in member.__doc__, f"{value} is not explained in {member.__doc__}"


def test_every_public_constant_is_in_the_readme():
    readme = open(README).read()
    constants = [n for n in dir(hamal) if not n.startswith("_") and n.isupper()]
    assert {"STATUS_CODES", "UPDATE_KINDS", "FACTOR_KINDS"} <= set(constants)
    assert [c for c in constants if c not in readme] == []


def _warns_once(call, message):
    with warnings.catch_warnings(record=True) as caught:
        warnings.simplefilter("always")
        result = call()
    deprecations = [w for w in caught if issubclass(w.category, DeprecationWarning)]
    assert len(deprecations) == 1 and message in str(deprecations[0].message), [str(w.message) for w in caught]
    assert deprecations[0].filename == __file__  # points at the caller's line
    return result


def test_status_ok_is_a_property_and_calling_it_still_works_with_a_warning(world):
    g, _ = world
    ok = hamal.run(g, "cholesky").results[-1].status
    with warnings.catch_warnings():
        warnings.simplefilter("error")
        assert ok.ok and ok.ok == True and bool(ok) is True  # noqa: E712
        assert repr(ok.ok) == "True" and hash(ok.ok) == hash(True) and ok.ok != False  # noqa: E712
        assert ok.ok + ok.ok == 2 and isinstance(ok.ok, int) and ok.ok != "yes"
    assert _warns_once(lambda: ok.ok(), "status.ok") is True
    failed = hamal.backend("cholesky").update(
        hamal.Step(0, hamal.Values.from_numpy([[0, 0, 0], [1, 0, 0]]),
                   [hamal.between(hamal.x(0), hamal.x(1), hamal.Pose2(1, 0, 0), [[1, 0, 0], [0, 1, 0], [0, 0, 1]])]))
    assert not failed.status.ok and failed.status.ok == False  # noqa: E712 (no prior: a gauge freedom)
    assert _warns_once(lambda: failed.status.ok(), "status.ok") is False


def test_sizes_are_len_and_the_old_methods_warn(world):
    g, _ = world
    values = hamal.Values.from_numpy([[0, 0, 0], [1, 0, 0]])
    assert len(values) == 2
    assert _warns_once(values.size, "len(values)") == 2
    assert _warns_once(values.empty, "len(values) == 0") is False
    source = hamal.ThesisProtocol(g)
    assert _warns_once(source.size, "len(source)") == len(source) == 12


def test_properties_are_cheap_reads_and_methods_compute():
    """The rule of python/README.md on the members the issue named."""
    assert isinstance(vars(hamal.Factor)["keys"], property)       # the factor's own keys
    assert isinstance(vars(hamal.Graph)["factors"], property)     # what the graph holds
    assert not isinstance(vars(hamal.Graph)["keys"], property)    # a sorted union: computed
    assert not isinstance(vars(hamal.Values)["keys"], property)   # a new sorted list
    assert isinstance(vars(hamal.Status)["ok"], property)
    assert isinstance(vars(hamal.JacobianCheckResult)["ok"], property)
    assert not isinstance(vars(hamal.PhaseTimes)["total"], property)  # a sum: computed
