"""The torque model's terms in the order of their columns, one line each: the term's word
in the command line's ``--friction`` text, and its module and class in
``sedsabso_jax.identification._model``.

Written without imports, so that the command line knows the words without importing JAX
(``cli/_vocabulary.py``); the model imports the classes
(:data:`sedsabso_jax.identification.TERMS`) and checks each class's ``name`` is its word.
A term of the package is its own file and its line here.
"""

#: ``(word, module, class)`` of each of the package's terms, in the order of their columns.
DECLARED: tuple[tuple[str, str, str], ...] = (
    ("offset", "_offset", "Offset"),
    ("quadratic", "_friction", "Quadratic"),
    ("smooth", "_friction", "SmoothCoulomb"),
    ("armature", "_actuators", "Armature"),
    ("coupling", "_actuators", "CoupledMotorFriction"),
    ("stribeck", "_friction", "Stribeck"),
    ("load", "_load", "LoadFriction"),
    ("presliding", "_presliding", "Presliding"),
)
#: The rigid-body model's own friction, always in the model (the base regressor's columns).
BASE_FRICTION = "viscous-coulomb"
#: The words of ``--friction``'s ``a+b`` text, in column order.
FRICTION_TERMS: tuple[str, ...] = (BASE_FRICTION, *(word for word, _, _ in DECLARED))
