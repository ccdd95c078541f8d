"""Protocol clients: drivers that implement the Mount API over a link to a real device."""
