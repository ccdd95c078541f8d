"""Soak: a simulated night of a SynScan mount behind every server, under client load and faults.

Run ``.venv/bin/python -m bench.soak`` (10 simulated hours at x100: 6 minutes) or
``--hours H --rate X --seed N``; ``--quick`` is the 1-hour x200 run the test suite makes. The stack
is the one a user runs, each part in its own process:

    python -m bench.soak --emulator   the SynScan emulator at --clock-rate X, as 'scopelink
                                      emulate synscan --tcp' runs it, faults switched on stdin
      <- scopelink serve --device synscan:tcp://...  (the process under test)
        <- this process: Alpaca, LX200, Stellarium, SynScan and dashboard WebSocket clients

The emulated sky runs X times faster than real time; the driver, the servers and the clients run
in real time, so a 180 degree slew at the EQ6's 3.4 deg/s lands in about half a real second at
x100. Seeded probabilistic faults of every kind, each fired a fixed number of times, and two
outages (stall, halt) come in the first 70 % of the night; then every fault is cleared and the
rest of the night shows recovery. See ``docs/reliability-soak.md`` for the checks and bounds.
"""
