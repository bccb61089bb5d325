"""The Entity: one launch-file element, whatever front end (XML or YAML) it was read from.

The interpreter only ever sees Entities, so both front ends share every tag rule. Attribute
values stay the raw strings written in the file (substitutions unresolved) so that
``orchestra convert`` can round-trip a file without changing its meaning.
"""
from __future__ import annotations

from dataclasses import dataclass, field

from orchestra.errors import Location


@dataclass
class Entity:
    """A tag with its attributes (name -> raw string, in file order), children and text.

    ``text`` is the element's own text (inline YAML of ``<rosparam>``), ``None`` when empty.
    ``location`` points at the element's start tag; errors about an attribute use it too.
    """

    tag: str
    attributes: dict[str, str] = field(default_factory=dict)
    children: list[Entity] = field(default_factory=list)
    text: str | None = None
    location: Location = field(default_factory=lambda: Location("<unknown>"))

    def get(self, name: str, default: str | None = None) -> str | None:
        """The raw value of attribute ``name``, or ``default`` when it is not written."""
        return self.attributes.get(name, default)

    def has(self, name: str) -> bool:
        return name in self.attributes
