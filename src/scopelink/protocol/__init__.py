"""Sans-IO protocol codecs: bytes <-> typed messages, no I/O and no clock."""
