"""``scopelink pointing``: the PC-side syncs of a running ``scopelink serve``, each with its
residual, and the pointing model they fit; ``remove N`` and ``clear`` (docs/pointing.md).

The model lives in the process that holds the mount, so this command talks to that process:
through the dashboard's JSON API (``GET``/``POST /api/pointing``) at ``--url`` (default: this
machine's dashboard port). Nothing else offers a way in: the SynScan, LX200 and Alpaca protocols
have no verb for a pointing model. A dashboard that needs pairing takes ``--pairing TOKEN``.
"""

from __future__ import annotations

import argparse
import json
import urllib.error
import urllib.request
from typing import Any

from scopelink.cli.commands import CommandParsers
from scopelink.cli.errors import CommandError

__all__ = ["register"]

_TIMEOUT_S = 5.0


def register(commands: CommandParsers) -> None:
    parser = commands.parser(
        "pointing",
        description=(
            "Show the syncs scopelink keeps on the PC for the mount of a running 'scopelink "
            "serve', each with its residual, and the pointing model fitted to them; remove one "
            "sync or clear them all."
        ),
        epilog=(
            "examples:\n  scopelink pointing\n  scopelink pointing remove 3\n"
            "  scopelink pointing clear --url http://127.0.0.1:8081\n"
        ),
        formatter_class=argparse.RawDescriptionHelpFormatter,
    )
    parser.add_argument(
        "action", nargs="?", choices=("list", "remove", "clear"), default="list", help="list"
    )
    parser.add_argument("number", nargs="?", type=int, help="the sync to remove (as listed)")
    parser.add_argument(
        "--url",
        default=None,
        help="the dashboard of a serve (default: the one this user runs, else port 8080 here)",
    )
    parser.add_argument("--pairing", default=None, help="the pairing token serve printed")
    parser.add_argument("--json", action="store_true", help="print the model as JSON")
    parser.set_defaults(run=_run)


def _run(args: argparse.Namespace) -> int:
    if args.action == "remove":
        if args.number is None:
            raise CommandError("say which sync to remove", "e.g. scopelink pointing remove 2")
        summary = _ask(args, {"remove": args.number})
    elif args.number is not None:
        raise CommandError(f"'{args.action}' takes no number")
    elif args.action == "clear":
        summary = _ask(args, {"clear": True})
    else:
        summary = _ask(args, None)
    if args.json:
        print(json.dumps(summary, indent=1))
    else:
        print(describe(summary))
    return 0


def _ask(args: argparse.Namespace, body: dict[str, Any] | None) -> dict[str, Any]:
    from scopelink.cli.serve_command import DEFAULT_DASHBOARD_PORT  # noqa: PLC0415 - one definition
    from scopelink.cli.serve_mount import DIRECT  # noqa: PLC0415 - no proxy, no redirect
    from scopelink.web.dashboard import PAIRING_HEADER  # noqa: PLC0415 - only to run

    if args.url is None:
        args.url, token = _running_dashboard(DEFAULT_DASHBOARD_PORT)
        args.pairing = args.pairing or token
    url = args.url.rstrip("/") + "/api/pointing"
    if not url.startswith(("http://", "https://")):
        raise CommandError(f"--url {args.url!r} is not an http:// address")
    headers = {"Content-Type": "application/json"}
    if args.pairing:
        headers[PAIRING_HEADER] = args.pairing
    data = None if body is None else json.dumps(body).encode()
    request = urllib.request.Request(url, data=data, headers=headers)
    try:
        with DIRECT.open(request, timeout=_TIMEOUT_S) as response:
            answer = json.loads(response.read())
    except urllib.error.HTTPError as error:
        raise CommandError(_refusal(error)) from None
    except (urllib.error.URLError, OSError, ValueError) as error:
        reason = getattr(error, "reason", error)
        raise CommandError(
            f"no scopelink dashboard answers at {args.url}: {reason}",
            "is 'scopelink serve' running? give its dashboard with --url",
        ) from None
    if not isinstance(answer, dict):
        raise CommandError(f"{args.url} did not answer as a scopelink dashboard")
    return answer


def _running_dashboard(default_port: int) -> tuple[str, str | None]:
    """The dashboard (and pairing token) of this user's running serve (cli/serve_registry.py),
    as the other commands find it; else serve's default address on this machine."""
    from scopelink.cli.serve_registry import running_serves  # noqa: PLC0415 - light

    for entry in running_serves():
        if entry.dashboard is not None:
            token = entry.about.get("pairing")
            return entry.dashboard, token if isinstance(token, str) else None
    return f"http://127.0.0.1:{default_port}", None


def _refusal(error: urllib.error.HTTPError) -> str:
    try:
        message = json.loads(error.read()).get("error")
    except (ValueError, AttributeError, OSError):
        message = None
    return str(message or f"the dashboard answered {error.code} {error.reason}")


def describe(summary: dict[str, Any]) -> str:
    """The model as a few lines of text."""
    syncs = summary.get("syncs") or []
    if not syncs:
        return "no syncs kept on the PC: readings and gotos are not corrected"
    lines = [f"{len(syncs)} sync(s) kept on the PC; RMS {summary['rms_arcmin']:.2f}′"]
    terms = summary.get("terms_arcmin") or {}
    fitted = summary.get("fitted") or []
    lines.append("terms  " + "  ".join(f"{name} {terms[name]:+.2f}′" for name in fitted))
    lines.append("  #  time (UTC)           RA (h)     Dec (°)    residual")
    for sync in syncs:
        lines.append(
            f"{sync['number']:>3}  {sync['at'][:19]:<19}  {sync['ra_j2000_hours']:>8.4f}  "
            f"{sync['dec_j2000_deg']:>+9.4f}  {sync['residual_arcmin']:>7.2f}′"
        )
    return "\n".join(lines)
