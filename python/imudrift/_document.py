"""A result that holds a command's JSON document (``to_dict()``, keys read as attributes)."""

import json


class Document:
    """A result holding a command's JSON document: its keys read as attributes."""

    def __init__(self, text):
        self._doc = json.loads(text)

    def to_dict(self):
        """The command's ``--json`` document (a fresh copy)."""
        return json.loads(json.dumps(self._doc))

    def __getattr__(self, name):
        doc = self.__dict__.get("_doc", {})
        if name in doc:
            return doc[name]
        raise AttributeError(name)
