"""visproxy: visibility proxies for shadow rays (see README.md in this package's source, lib/python/README.md)."""

from .visproxy import *  # noqa: F401,F403 (the compiled module's functions and exceptions)
from .visproxy import __doc__, __version__  # noqa: F401
