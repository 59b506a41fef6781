"""XML parsing that remembers each element's line, for messages that say where a problem is."""
import xml.etree.ElementTree as ET
from xml.parsers import expat
from typing import Dict, Tuple


class XmlError(ValueError):
    """Malformed XML or an unusable element; the message names the file, line and element."""


def parse_xml(text: str, source: str) -> Tuple[ET.Element, Dict[ET.Element, int]]:
    """Parses `text` (from `source`, a file name or description) into (root, {element: line})."""
    builder = ET.TreeBuilder()
    lines: Dict[ET.Element, int] = {}
    parser = expat.ParserCreate()

    def start(tag, attrs):
        lines[builder.start(tag, attrs)] = parser.CurrentLineNumber

    parser.StartElementHandler = start
    parser.EndElementHandler = builder.end
    parser.CharacterDataHandler = builder.data
    try:
        parser.Parse(text, True)
    except expat.ExpatError as e:
        raise XmlError('%s:%d: malformed XML: %s' % (source, e.lineno, expat.ErrorString(e.code))) from None
    return builder.close(), lines


def where(source: str, lines: Dict[ET.Element, int], element: ET.Element) -> str:
    """'file:line: <tag name="...">' for messages."""
    name = element.get('name')
    tag = '<%s name="%s">' % (element.tag, name) if name else '<%s>' % element.tag
    return '%s:%s: %s' % (source, lines.get(element, '?'), tag)


def child_text(element: ET.Element, tag: str, default=None):
    child = element.find(tag)
    return child.text.strip() if child is not None and child.text is not None else default


def floats(text: str, count: int, what: str):
    """Parses exactly `count` floats from whitespace-separated text, or raises XmlError naming `what`."""
    try:
        values = [float(v) for v in text.split()]
    except ValueError:
        raise XmlError('%s: expected %d numbers, got "%s"' % (what, count, text)) from None
    if len(values) != count:
        raise XmlError('%s: expected %d numbers, got %d ("%s")' % (what, count, len(values), text))
    return values
