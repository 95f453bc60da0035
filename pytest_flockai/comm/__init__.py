"""Radio links between the drone and the ground station."""

from .link import LINKS, Link, Transfer, link, links

__all__ = ["LINKS", "Link", "Transfer", "link", "links"]
