"""Contact with obstacles and with the hose itself: the contact model of a set of obstacles for the
solver (model.py) and continuation with contact switched on (continuation.py).  The kernels and the
Newton iteration are in mechanics/contact.py and mechanics/contact_newton.py."""
