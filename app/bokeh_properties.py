"""Shortcuts in Bokeh's property machinery, which takes most of a new session's server
CPU (bench/bench_sessions.py --profile; --compare-fixes measures them): the same values,
computed once or not at all.

They replace private parts of Bokeh ``panel_fixes.BOKEH_VERSION`` (3.9.2) and hold for
that release only: ``panel_fixes.check_version()`` fails loudly on another one, and
tests/app/test_bokeh_properties.py checks that the parts replaced are as written for.
"""
from __future__ import annotations

import bokeh.model.util as _model_util
from bokeh.core.has_props import HasProps as _HasProps, Intrinsic as _Intrinsic, \
    Undefined as _Undefined
from bokeh.core.property.descriptors import DataSpecPropertyDescriptor, PropertyDescriptor
from bokeh.core.property.wrappers import PropertyValueContainer as _PropertyValueContainer

#: The descriptors whose ``__set__`` is ``PropertyDescriptor.__set__``.
_PLAIN_DESCRIPTORS = (PropertyDescriptor, DataSpecPropertyDescriptor)


def _cached_overridden_defaults(cls):
    found = cls.__dict__.get("_ie_overridden_defaults")
    if found is None:
        found = _BOKEH_ORIGINALS["_overridden_defaults"](cls)
        cls._ie_overridden_defaults = found
    return found


def _selected_properties_with_values(self, query, *, include_defaults=True,
                                     include_undefined=False):
    if include_defaults:
        return _BOKEH_ORIGINALS["query_properties_with_values"](
            self, query, include_defaults=True, include_undefined=include_undefined)
    from bokeh.core.has_props import PropertyValueContainer, Undefined
    from bokeh.core.property.descriptors import UnsetValueError

    themed = self.themed_values() or {}
    selected = set(self._property_values) | set(self._unstable_default_values) | set(themed)
    result = {}
    for key in self.properties(_with_props=True):
        if key not in selected:                    # upstream reads the value, then skips it
            continue
        descriptor = self.lookup(key)
        if not query(descriptor):
            continue
        try:
            value = descriptor.get_value(self)
        except UnsetValueError:
            if not include_undefined:
                raise
            value = Undefined
        if (key not in themed and isinstance(value, PropertyValueContainer)
                and key in self._unstable_default_values):
            continue
        result[key] = value
    return result


def _unstable_default_names(cls) -> tuple:
    """Names of the properties of ``cls`` whose default is made per instance (a model,
    a list), in Bokeh's order: what ``HasProps.__init__`` fills in for each new model
    (upstream asks every property each time; the answer depends on the class only)."""
    found = cls.__dict__.get("_ie_unstable_defaults")
    if found is None:
        found = tuple(name for name in cls.properties(_with_props=True)
                      if cls.lookup(name).has_unstable_default(cls))
        cls._ie_unstable_defaults = found
    return found


def _empty_container(prop) -> bool:
    # (a default given as a function or a model is not looked into: made as upstream);
    # a default Bokeh keeps unwrapped (a Seq's list) is sent with the page: made too
    default = prop._default
    return (type(default) in (list, dict, set) and not default
            and isinstance(prop.wrap(type(default)()), _PropertyValueContainer))


def _eager_default_names(cls) -> tuple:
    """Of :func:`_unstable_default_names`, those whose default is not an empty list, dict
    or set (a model, or a container that holds something): made when a model is built.
    An empty container holds no reference and is left at its default until read."""
    found = cls.__dict__.get("_ie_eager_defaults")
    if found is None:
        found = tuple(name for name in _unstable_default_names(cls)
                      if not _empty_container(cls.lookup(name).property))
        cls._ie_eager_defaults = found
        cls._ie_lazy_defaults = frozenset(_unstable_default_names(cls)) - set(found)
    return found


def _lazy_default_names(cls) -> frozenset:
    if "_ie_lazy_defaults" not in cls.__dict__:
        _eager_default_names(cls)
    return cls._ie_lazy_defaults


def _visit_made_references(value, visitor) -> None:
    # upstream reads every property that may hold a model, which makes each empty
    # container default it has not made yet: such a default holds no reference
    if isinstance(value, _HasProps):
        lazy = _lazy_default_names(type(value))
        made, unstable = value._property_values, value._unstable_default_values
        themed = value.__dict__.get("__themed_values__") or ()
        for attr in value.properties_with_refs():
            if attr in lazy and attr not in made and attr not in unstable and attr not in themed:
                continue
            _model_util.visit_value_and_its_immediate_references(getattr(value, attr), visitor)
    else:
        _model_util.visit_value_and_its_immediate_references(value, visitor)


def _lighter_init(self, **properties) -> None:
    super(_HasProps, self).__init__()
    self._property_values = {}
    self._unstable_default_values = {}
    self._unstable_themed_values = {}
    unstable = _unstable_default_names(type(self))
    for name, value in properties.items():
        if value is _Undefined or value is _Intrinsic:
            continue
        descriptor = self.lookup(name, raises=False)
        if (isinstance(value, _HasProps) and type(descriptor) in _PLAIN_DESCRIPTORS
                and name in unstable):
            # upstream first makes the default (a new model) to compare the value with
            # (a model passed in is never equal to it), then drops it
            descriptor._set_value(self, descriptor.property.prepare_value(self, name, value))
        else:
            setattr(self, name, value)
    for name in _eager_default_names(type(self)):
        if name not in properties:
            self.lookup(name)._get(self)     # fills in ``_unstable_*_values``
    self._initialized = True


def _stable_default(self, obj):
    themed = obj.__dict__.get("__themed_values__")
    cls = type(obj)
    if themed is None or self.name not in themed:
        made = obj._unstable_default_values            # this instance's, made once
        if self.name in made:
            return made[self.name]
        known = cls.__dict__.get("_ie_stable_defaults")
        if known is None:
            known = {}
            cls._ie_stable_defaults = known
        if self.name in known:
            return known[self.name]
        if self.name not in obj._property_values and \
                self.name not in _unstable_default_names(cls):
            # an immutable value (str, number, None, tuple): the same for every instance
            known[self.name] = value = self.instance_default(obj)
            return value
    return _BOKEH_ORIGINALS["_get_default"](self, obj)


def _themed_values(self):
    # upstream: getattr(self, "__themed_values__", None), an AttributeError raised
    # through HasProps.__getattr__ for every model without a theme, at every default read
    return self.__dict__.get("__themed_values__")


_BOKEH_ORIGINALS: dict = {}


def lighter_properties(on: bool = True) -> None:
    """Shortcuts in Bokeh 3.9.2's property machinery, which takes most of a new
    session's server CPU (bench/bench_sessions.py --profile; --compare-fixes measures
    them). Same values, computed once or not at all:

    1. ``HasProps._overridden_defaults()`` walks the class's MRO and merges every
       ``__overridden_defaults__`` on each call, about 50 times per model built or
       sent; the classes never change, so the merge is kept per class.
    2. ``HasProps.query_properties_with_values(include_defaults=False)`` (what the
       document's serialisation calls) reads the default value of every property of the
       model, then drops those not set: it reads only the ones it keeps.
    3. ``HasProps.__init__`` sets each keyword through the property's setter, which
       first makes the old value: a model given its ticker, range or view made a
       default one first and dropped it (a page made about 420 models to keep 180).
       A model passed for a property whose default is made per instance is stored
       without that; and which properties have such defaults is asked once per class,
       not of every property of every new model.
    4. ``HasProps.themed_values()`` raised and caught an AttributeError (through
       ``HasProps.__getattr__``) for every model without a theme, on every read of a
       default: it reads the instance's dict.
    5. ``PropertyDescriptor._get_default`` copies and validates the class's default on
       every read of a property left at an immutable default (str, number, None,
       tuple), thousands of times per page: kept per class, unless a theme sets it;
       a default made per instance (a list, a model) is looked up first.

    6. ``HasProps.__init__`` also makes every empty list, dict and set default of the new
       model (its tags, callbacks, CSS classes, styles...: about ten per model, most
       never set), and the walk that collects a document's models reads each of them:
       they are made when first read, and the walk skips those not made (an empty
       container refers to no model). A default that is a model, or a container holding
       something, is still made with the model.

    tests/app/test_bokeh_properties.py checks they give Bokeh's own results for every model
    of a session's page, and the same serialised page. ``on=False`` restores Bokeh's
    functions (for measuring). Idempotent, per process.
    """
    from bokeh.core.has_props import HasProps

    if not _BOKEH_ORIGINALS:
        _BOKEH_ORIGINALS["_overridden_defaults"] = HasProps._overridden_defaults.__func__
        _BOKEH_ORIGINALS["query_properties_with_values"] = \
            HasProps.query_properties_with_values
        _BOKEH_ORIGINALS["__init__"] = HasProps.__init__
        _BOKEH_ORIGINALS["themed_values"] = HasProps.themed_values
        _BOKEH_ORIGINALS["_get_default"] = PropertyDescriptor._get_default
        _BOKEH_ORIGINALS["visit_immediate_value_references"] = \
            _model_util.visit_immediate_value_references
    if on:
        HasProps._overridden_defaults = classmethod(_cached_overridden_defaults)
        HasProps.query_properties_with_values = _selected_properties_with_values
        HasProps.__init__ = _lighter_init
        HasProps.themed_values = _themed_values
        PropertyDescriptor._get_default = _stable_default
        _model_util.visit_immediate_value_references = _visit_made_references
    else:
        HasProps._overridden_defaults = classmethod(_BOKEH_ORIGINALS["_overridden_defaults"])
        HasProps.query_properties_with_values = \
            _BOKEH_ORIGINALS["query_properties_with_values"]
        HasProps.__init__ = _BOKEH_ORIGINALS["__init__"]
        HasProps.themed_values = _BOKEH_ORIGINALS["themed_values"]
        PropertyDescriptor._get_default = _BOKEH_ORIGINALS["_get_default"]
        _model_util.visit_immediate_value_references = \
            _BOKEH_ORIGINALS["visit_immediate_value_references"]
