"""Device servers: turn bytes from a link into calls on a :class:`~scopelink.mount.Mount`.

In front of the simulated mount a server is a device emulator; in front of a real one, a bridge.
"""
