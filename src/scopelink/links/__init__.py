"""Byte links: serial ports, TCP, pseudo-terminals and in-memory pairs, with optional wire pacing."""
