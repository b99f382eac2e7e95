"""The kick explorer: a local web page to run, watch and compare kicks (``whipple-kick-explorer``).

The app at the top of the wings: it may import every wing, and nothing imports it (a plain run never
loads it, nor its web library). One module per concept: :mod:`.form` (the page's fields, derived from the
Scenario's declarations, and the parsing of what the page sends, with the command line's messages),
:mod:`.jobs` (the work a request hands to the sweeps' process pool: a run and its files, the overlay, the
stability against speed, the animation), :mod:`.study` (an uncertainty study's P(best) for the chosen
load), :mod:`.page` (the page itself: HTML, CSS and script, nothing loaded from the internet) and
:mod:`.server` (the Tornado application and the console script). docs/explorer.md describes it.
"""
