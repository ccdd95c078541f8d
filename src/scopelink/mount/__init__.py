"""The protocol-neutral Mount API that every front end uses."""
