"""What a web process loads before it takes its first request.

Django imports the views on the first request that resolves a URL, and the
views import the reports' figures and statistics (matplotlib, scipy.stats),
which the first visitor after a (re)start would wait for on top of their own
page.  Done while the process starts, before it listens, nobody waits.
"""

from django.template.loader import get_template
from django.urls import resolve, reverse

from gui.views.pages import module_graph

# The pages a visitor opens first after a restart: signing in, then the cockpit.
FIRST_TEMPLATES = ("registration/login.html", "gui/index.html")


def warm_up() -> None:
    """Import every view (through the URL configuration), index the URL names
    for reversing, compile the first pages' templates and read the cockpit's
    module list.  Repeating it costs nothing: each step keeps its result for
    the life of the process."""
    # Loading the root configuration imports every included one with its views.
    resolve("/")
    # The first reverse() indexes every pattern, which the first page would pay;
    # a namespaced name indexes its namespace too.
    reverse("admin:index")
    for name in FIRST_TEMPLATES:
        get_template(name)
    module_graph("gui/main.js")
