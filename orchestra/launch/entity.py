"""The Entity: one launch-file element, whatever front end (XML or YAML) it was read from.

The interpreter only ever sees Entities, so both front ends share every tag rule. Attribute
values stay the raw strings written in the file (substitutions unresolved) so that
``orchestra convert`` can round-trip a file without changing its meaning.
"""
from __future__ import annotations

from dataclasses import dataclass, field
from typing import Protocol

from orchestra.errors import Location


class SourcePositions(Protocol):
    """Where a front end read an element: its start tag and its attribute names. One object
    may serve every element of a file (asked with the element), so reading a file does not
    make one per element."""

    def start(self, entity: Entity) -> Location: ...

    def attribute(self, entity: Entity, name: str) -> Location | None: ...


@dataclass(slots=True)
class Entity:
    """A tag with its attributes (name -> raw string, in file order), children and text.

    ``text`` is the element's own text (inline YAML of ``<rosparam>``), ``None`` when empty.
    ``location`` points at the element's start tag (the line it begins on, which the plan
    records); ``positions``, when the front end knows them, give the exact
    position of the start tag and of each attribute name, so errors and ``orchestra check``
    point at the column without reading the file again. Positions are not part of equality:
    the same element read from XML or YAML is equal.
    """

    tag: str
    attributes: dict[str, str] = field(default_factory=dict)
    children: list[Entity] = field(default_factory=list)
    text: str | None = None
    location: Location = field(default_factory=lambda: Location("<unknown>"))
    positions: SourcePositions | None = field(default=None, compare=False, repr=False)

    def get(self, name: str, default: str | None = None) -> str | None:
        """The raw value of attribute ``name``, or ``default`` when it is not written."""
        return self.attributes.get(name, default)

    def has(self, name: str) -> bool:
        return name in self.attributes

    def where(self, attribute: str | None = None) -> Location:
        """The most exact known position of ``attribute`` (or of the start tag)."""
        if self.positions is None:
            return self.location
        if attribute is not None and attribute in self.attributes:
            found = self.positions.attribute(self, attribute)
            if found is not None:
                return found
        return self.positions.start(self)

    @property
    def attribute_locations(self) -> dict[str, Location]:
        """Exact positions of the attributes the front end located."""
        if self.positions is None:
            return {}
        found = {name: self.positions.attribute(self, name) for name in self.attributes}
        return {name: where for name, where in found.items() if where is not None}
