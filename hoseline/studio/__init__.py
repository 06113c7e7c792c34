"""The studio: a local web page to place a hose by hand, with the solver following every change.

session.py holds the problem being edited and the hose's equilibrium (each change a step of
continuation, procedures/placement/tracking.py); view.py turns it into the messages the page
draws; comparison.py says how a fresh placement differs from the shape shown; messages.py checks what the page sends; inbox.py coalesces a burst of drags; uploads.py
reads dropped files with the command line's readers; server.py is the Starlette app (HTTP and
the WebSocket of the solve loop) and launch.py runs it on uvicorn.  static/ holds the page
(plain ES modules) and the vendored three.js.

May import: everything below it (model, procedures, io, report, demos).  Nothing imports it
but commands/studio.py.
"""
