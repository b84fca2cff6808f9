"""Server-rendered pages of the operator GUI (the JSON API is in events.api)."""
