"""A Bokeh document kept as plain data: what the light load client (rel_light_client.py)
holds instead of Bokeh models.

Bokeh's wire format (``bokeh.core.serialization``) is decoded into dicts, lists, numpy
arrays over the received buffers and ``Ref``s; a model is an id with a type name and a
dict of the attributes the server sent (Bokeh sends only those not at their default).
The patch events a server sends are applied to that store: ModelChanged,
ColumnDataChanged, ColumnsStreamed, ColumnsPatched, RootAdded, RootRemoved,
TitleChanged (MessageSent carries nothing for the document). ``LightModel`` reads a
model like a Bokeh model (``doc.get_model_by_name("phase").data_source.data``), so the
load script asks both clients the same questions; setting an attribute on it sends a
ModelChanged patch, as a Bokeh client session (or BokehJS) does for a widget's value.
"""
from __future__ import annotations

import base64
import gzip
import sys

import numpy as np

#: What a model reads for an attribute the server did not send (its Bokeh default),
#: for the attributes the load script and the tests read.
DEFAULTS = {"name": None, "visible": True, "css_classes": (), "children": (), "data": {},
            "text": "", "title": None, "location": None, "value": None, "tags": ()}


class Ref:
    """A reference to a model by id (Bokeh's ``{"id": ...}``)."""
    __slots__ = ("id",)

    def __init__(self, id_: str):
        self.id = id_

    def __repr__(self) -> str:
        return f"Ref({self.id})"


class LightModel:
    """One model of a ``LightDocument``, read like a Bokeh model: references come back
    as ``LightModel``s; setting an attribute changes the store and sends it."""
    __slots__ = ("_doc", "id", "__view_model__")

    def __init__(self, doc: "LightDocument", id_: str):
        object.__setattr__(self, "_doc", doc)
        object.__setattr__(self, "id", id_)
        object.__setattr__(self, "__view_model__", doc.types[id_].rsplit(".", 1)[-1])

    def __getattr__(self, attr: str):
        attrs = self._doc.attrs[self.id]
        if attr in attrs:
            return self._doc.wrap(attrs[attr])
        if attr in DEFAULTS:
            return DEFAULTS[attr]
        raise AttributeError(f"{self.__view_model__}({self.id}) has no {attr!r} from the server")

    def __setattr__(self, attr: str, value) -> None:
        self._doc.set_local(self.id, attr, value)

    def __eq__(self, other) -> bool:
        return isinstance(other, LightModel) and other.id == self.id

    def __hash__(self) -> int:
        return hash(self.id)

    def __repr__(self) -> str:
        return f"{self.__view_model__}(id={self.id!r})"


class LightDocument:
    """Models as ``id -> attributes``; roots, title; a name index for
    ``get_model_by_name``. ``send(events)`` is given by the session (local changes);
    ``on_change(id, attr)`` hooks run after a server's ModelChanged (see the session)."""

    def __init__(self):
        self.attrs: dict[str, dict] = {}
        self.types: dict[str, str] = {}
        self.names: dict[str, str] = {}
        self.roots: list[str] = []
        self.title = ""
        self.send = None
        self.hooks: list = []

    # -- decoding Bokeh's wire format ---------------------------------------------------
    def decode(self, obj, buffers: dict):
        if isinstance(obj, list):
            return [self.decode(x, buffers) for x in obj]
        if not isinstance(obj, dict):
            return obj
        kind = obj.get("type")
        if kind is None:
            if "id" in obj:
                return Ref(obj["id"])
            return {k: self.decode(v, buffers) for k, v in obj.items()}
        if kind == "object":
            attrs = {k: self.decode(v, buffers) for k, v in obj.get("attributes", {}).items()}
            if "id" not in obj:                        # a plain object: its fields
                return attrs
            self._register(obj["id"], obj["name"], attrs)
            return Ref(obj["id"])
        if kind == "map":
            return {_key(self.decode(k, buffers)): self.decode(v, buffers)
                    for k, v in obj.get("entries", [])}
        if kind in ("array", "set"):
            return [self.decode(x, buffers) for x in obj.get("entries", [])]
        if kind == "number":
            return float(obj["value"]) if isinstance(obj["value"], str) else obj["value"]
        if kind == "ref":
            return Ref(obj["id"])
        if kind == "bytes":
            data = obj["data"]
            if isinstance(data, str):
                return gzip.decompress(base64.b64decode(data))
            return buffers[data["id"]]
        if kind in ("ndarray", "typed_array"):
            data = self.decode(obj["array"], buffers)
            if isinstance(data, (bytes, bytearray, memoryview)):
                array = np.frombuffer(data, dtype=obj["dtype"])
                if obj.get("order", sys.byteorder) != sys.byteorder:
                    array = array.byteswap()
            else:
                array = np.array(data, dtype=obj["dtype"])
            shape = obj.get("shape")
            return array.reshape(shape) if shape and len(shape) > 1 else array
        if kind == "slice":
            return slice(*(self.decode(obj.get(k), buffers) for k in ("start", "stop", "step")))
        return {k: self.decode(v, buffers) for k, v in obj.items()}   # value, field, expr...

    def _register(self, id_: str, type_name: str, attrs: dict) -> None:
        self.attrs[id_] = attrs
        self.types[id_] = type_name
        if attrs.get("name") is not None:
            self.names[attrs["name"]] = id_

    # -- the document ---------------------------------------------------------------------
    def load(self, doc_json: dict, buffers: dict) -> None:
        """The document of a PULL-DOC-REPLY (``content["doc"]``)."""
        self.title = doc_json.get("title", "")
        if "config" in doc_json:
            self.decode(doc_json["config"], buffers)
        self.roots = [self.decode(r, buffers).id for r in doc_json.get("roots", [])]

    def wrap(self, value):
        if isinstance(value, Ref):
            return LightModel(self, value.id) if value.id in self.attrs else None
        if isinstance(value, list):
            return [self.wrap(v) for v in value]
        return value

    def get_model_by_name(self, name: str):
        id_ = self.names.get(name)
        return LightModel(self, id_) if id_ is not None else None

    def reachable(self) -> list[str]:
        """Ids of every model reachable from the roots (Bokeh's ``doc.models``)."""
        seen: set[str] = set()
        stack = list(self.roots)
        while stack:
            id_ = stack.pop()
            if id_ in seen or id_ not in self.attrs:
                continue
            seen.add(id_)
            _refs(self.attrs[id_], stack)
        return sorted(seen)

    @property
    def models(self) -> list[LightModel]:
        return [LightModel(self, i) for i in self.reachable()]

    def set_local(self, id_: str, attr: str, value) -> None:
        """A change made here (a slider moved): stored, and sent as a ModelChanged."""
        self.attrs[id_][attr] = value
        if attr == "name":
            self.names[value] = id_
        self.send([{"kind": "ModelChanged", "model": {"id": id_}, "attr": attr, "new": value}])

    # -- the server's patches -------------------------------------------------------------
    def apply(self, events: list, buffers: dict) -> None:
        for event in events:
            self.apply_event(self.decode(event, buffers))

    def apply_event(self, ev: dict) -> None:
        kind = ev["kind"]
        if kind == "ModelChanged":
            id_, attr = ev["model"].id, ev["attr"]
            self.attrs[id_][attr] = ev["new"]
            if attr == "name" and ev["new"] is not None:
                self.names[ev["new"]] = id_
            for hook in self.hooks:
                hook(id_, attr)
        elif kind == "ColumnDataChanged":
            attrs, attr = self.attrs[ev["model"].id], ev["attr"]
            if ev.get("cols") is not None:             # only these columns change
                data = dict(attrs.get(attr, {}))
                data.update({c: ev["data"][c] for c in ev["cols"] if c in ev["data"]})
                attrs[attr] = data
            else:
                attrs[attr] = ev["data"]
        elif kind == "ColumnsStreamed":
            attrs, rollover = self.attrs[ev["model"].id], ev.get("rollover")
            old = attrs.get(ev["attr"], {})
            data = {}
            for col, new in ev["data"].items():
                column = np.concatenate([np.asarray(old.get(col, [])), np.asarray(new)])
                data[col] = column[-rollover:] if rollover else column
            attrs[ev["attr"]] = {**old, **data}
        elif kind == "ColumnsPatched":
            attrs = self.attrs[ev["model"].id]
            data = dict(attrs.get(ev["attr"], {}))
            for col, patches in ev["patches"].items():
                column = np.array(data[col], copy=True)
                for index, value in patches:
                    column[index if not isinstance(index, list) else tuple(index)] = value
                data[col] = column
            attrs[ev["attr"]] = data
        elif kind == "RootAdded":
            self.roots.append(ev["model"].id)
        elif kind == "RootRemoved":
            self.roots = [r for r in self.roots if r != ev["model"].id]
        elif kind == "TitleChanged":
            self.title = ev["title"]
        elif kind != "MessageSent":
            raise ValueError(f"patch event {kind!r} not known to the light client")


def _key(key):
    return tuple(key) if isinstance(key, list) else key


def _refs(value, out: list) -> None:
    """Append the ids of every Ref inside ``value`` (containers walked, arrays not)."""
    if isinstance(value, Ref):
        out.append(value.id)
    elif isinstance(value, dict):
        for v in value.values():
            _refs(v, out)
    elif isinstance(value, (list, tuple)):
        for v in value:
            _refs(v, out)
