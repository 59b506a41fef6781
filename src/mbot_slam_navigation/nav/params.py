"""Reading a ROS parameter namespace the way the navigation stack does, but checked.

Every key a node reads is declared with its default; what the user set but nobody reads is
reported with the nearest known key (``controller_patiente`` -> ``controller_patience``), or with
the namespace it belongs to when it is a known key of another one (``planner_frequency`` in
``local_costmap``). Wrong types name the key and its namespace. Frame ids lose a leading ``/``
(tf2 rejects them) with one warning each. ROS-free: the input is the dict ``rospy.get_param(ns)``
returns, the output plain values, warnings go to a callable.
"""
import difflib
from typing import Any, Callable, Dict, Iterable, List, Optional

Warn = Callable[[str], None]


class ParamError(ValueError):
    """A parameter whose value cannot be used; the message names the key and namespace."""


def nearest_key(key: str, known: Iterable[str]) -> Optional[str]:
    """The known key closest in spelling to ``key``, or None when nothing is close."""
    best = difflib.get_close_matches(key, list(known), n=1, cutoff=0.75)
    return best[0] if best else None


class ParamReader:
    """Typed reads from one namespace's dict, remembering which keys were read.

    ``ns`` is only used in messages (e.g. ``/move_base/local_costmap``).
    """

    def __init__(self, values: Optional[Dict[str, Any]], ns: str, warn: Warn):
        self.values = dict(values or {})
        self.ns = ns.rstrip('/') or '/'
        self.warn = warn
        self.read_keys = set()

    def where(self, key: str) -> str:
        return '%s/%s' % (self.ns, key) if self.ns != '/' else '/' + key

    def has(self, key: str) -> bool:
        return key in self.values

    def raw(self, key: str, default: Any = None) -> Any:
        self.read_keys.add(key)
        return self.values.get(key, default)

    def number(self, key: str, default: float, minimum: Optional[float] = None, positive: bool = False) -> float:
        value = self.raw(key, default)
        if isinstance(value, bool) or not isinstance(value, (int, float)):
            raise ParamError('parameter %s must be a number, got %r' % (self.where(key), value))
        value = float(value)
        if positive and not value > 0.0:
            raise ParamError('parameter %s must be positive, got %g' % (self.where(key), value))
        if minimum is not None and value < minimum:
            raise ParamError('parameter %s must be >= %g, got %g' % (self.where(key), minimum, value))
        return value

    def integer(self, key: str, default: int, minimum: Optional[int] = None) -> int:
        value = self.raw(key, default)
        if isinstance(value, bool) or not isinstance(value, int):
            if isinstance(value, float) and value.is_integer():
                value = int(value)
            else:
                raise ParamError('parameter %s must be an integer, got %r' % (self.where(key), value))
        if minimum is not None and value < minimum:
            raise ParamError('parameter %s must be >= %d, got %d' % (self.where(key), minimum, value))
        return value

    def boolean(self, key: str, default: bool) -> bool:
        value = self.raw(key, default)
        if isinstance(value, bool):
            return value
        if isinstance(value, str) and value.lower() in ('true', 'false'):
            return value.lower() == 'true'
        raise ParamError('parameter %s must be true or false, got %r' % (self.where(key), value))

    def string(self, key: str, default: str) -> str:
        value = self.raw(key, default)
        if not isinstance(value, str):
            raise ParamError('parameter %s must be a string, got %r' % (self.where(key), value))
        return value

    def frame(self, key: str, default: str) -> str:
        """A frame id; a leading '/' (tf1 style, tf2 rejects it) is stripped with a warning."""
        value = self.string(key, default)
        if value.startswith('/'):
            stripped = value.lstrip('/')
            self.warn('parameter %s: frame id "%s" has a leading "/", which tf2 does not accept; using "%s"'
                      % (self.where(key), value, stripped))
            value = stripped
        if not value:
            raise ParamError('parameter %s: empty frame id' % self.where(key))
        return value

    def deprecated(self, new: str, old: str, default: Any, kind: str = 'number') -> Any:
        """ROS's loadParameterWithDeprecation: the new name wins; the old one still works, with a warning."""
        read = getattr(self, kind)
        if self.has(new):
            if self.has(old):
                self.read_keys.add(old)
                self.warn('parameter %s is ignored because %s is set' % (self.where(old), self.where(new)))
            return read(new, default)
        if self.has(old):
            self.warn('parameter %s is deprecated; use %s' % (self.where(old), new))
            return read(old, default)
        return read(new, default)

    def report_unknown(self, skip: Iterable[str] = (), elsewhere: Optional[Dict[str, str]] = None) -> List[str]:
        """Warns about every key set but never read (except ``skip``, sub-namespaces handled by others).

        ``elsewhere`` maps keys of other namespaces to where they belong. Returns the unknown keys.
        """
        skip = set(skip)
        unknown = []
        for key in sorted(self.values):
            if key in self.read_keys or key in skip:
                continue
            unknown.append(key)
            if elsewhere and key in elsewhere:
                self.warn('parameter %s has no effect here: %s is a parameter of %s' % (self.where(key), key, elsewhere[key]))
                continue
            guess = nearest_key(key, self.read_keys | skip | set(elsewhere or ()))
            if guess and elsewhere and guess in elsewhere and guess not in self.read_keys:
                self.warn('unknown parameter %s (did you mean %s? that is a parameter of %s, not of this namespace); '
                          'it is ignored' % (self.where(key), guess, elsewhere[guess]))
            elif guess:
                self.warn('unknown parameter %s (did you mean %s?); it is ignored' % (self.where(key), guess))
            else:
                self.warn('unknown parameter %s; it is ignored' % self.where(key))
        return unknown
