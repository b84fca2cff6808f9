"""Helpers for asserting what a rendered page makes the browser fetch."""

import re

ASSET_URL = re.compile(r'<(?:script|link|img)[^>]+(?:src|href)="([^"]+)"')


def asset_urls(html: str) -> list[str]:
    return ASSET_URL.findall(html)


def external_assets(html: str) -> list[str]:
    """Scripts, stylesheets and images a page would load from another host.

    The field often has no internet, so every page must work from our own server.
    """
    return [url for url in asset_urls(html) if re.match(r"(?:https?:)?//", url)]
