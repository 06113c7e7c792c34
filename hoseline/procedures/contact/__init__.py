"""Contact with obstacles and with the hose itself: the contact model of a set of obstacles for the
solver (model.py), continuation with contact switched on (continuation.py), and obstacles that move
with a sweep's bodies (moving.py).  The kernels and the Newton iteration are in mechanics/contact.py,
mechanics/contact_newton.py and mechanics/contact_motion.py."""
