"""The planetarium's end of the LX200 codec: replies cut by the shape each command gets, in the
order the commands went, whatever the chunking; the handset's own reply encoders read back."""

from __future__ import annotations

from hypothesis import given
from hypothesis import strategies as st

from scopelink.protocol import lx200
from scopelink.protocol.lx200 import (
    DATE_SET_REPLY,
    NEED_DATA,
    LX200ClientConnection,
    LX200Reply,
    MalformedReply,
    SlewRefusal,
    UnexpectedReply,
    boolean_reply,
    slew_reply,
    text_reply,
)

EXCHANGES: list[tuple[lx200.AnyCommand, bytes]] = [
    (lx200.Get(lx200.Query.RA), text_reply("12:34:56")),
    (lx200.Halt(), b""),  # no reply at all: nothing is waited for
    (lx200.SetTargetRA(5.5), boolean_reply(True)),
    (lx200.GotoTarget(), slew_reply(None)),
    (lx200.GotoTarget(), slew_reply(SlewRefusal.BELOW_HORIZON, "Object below horizon")),
    (lx200.SetLocalDate(11, 24, 26), DATE_SET_REPLY),
    (lx200.SetLocalDate(11, 24, 26), boolean_reply(False)),
    (lx200.Get(lx200.Query.DEC), text_reply("+12*34:56")),
]


def _replies(client: LX200ClientConnection) -> list[lx200.connection.ClientEvent]:
    events = []
    while (event := client.next_event()) is not NEED_DATA:
        events.append(event)
    return events


@given(st.lists(st.integers(min_value=1, max_value=7), min_size=1, max_size=60))
def test_pipelined_replies_are_cut_by_their_commands_shapes_whatever_the_chunks(
    cuts: list[int],
) -> None:
    client = LX200ClientConnection()
    for command, _ in EXCHANGES:
        client.send(command)
    stream = b"".join(reply for _, reply in EXCHANGES)
    events: list[lx200.connection.ClientEvent] = []
    position = 0
    for cut in [*cuts, len(stream)]:
        client.receive_data(stream[position : position + cut])
        position += cut
        events += _replies(client)
        if position >= len(stream):
            break
    expected = [LX200Reply(command, reply) for command, reply in EXCHANGES if reply]
    assert events == expected
    assert client.waiting == 0


def test_bytes_with_no_command_waiting_and_an_endless_reply_are_reported() -> None:
    client = LX200ClientConnection()
    client.receive_data(b"1")
    assert _replies(client) == [UnexpectedReply(b"1")]
    command = lx200.Get(lx200.Query.RA)
    client.send(command)
    client.receive_data(b"x" * (lx200.MAX_REPLY_LENGTH + 1))
    (event,) = _replies(client)
    assert isinstance(event, MalformedReply)
    assert event.command == command
    assert client.waiting == 0


def test_send_gives_the_commands_bytes() -> None:
    assert LX200ClientConnection().send(lx200.Get(lx200.Query.RA)) == b":GR#"
