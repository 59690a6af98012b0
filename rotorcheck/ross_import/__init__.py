"""Import a rotor saved by ROSS (ross-rotordynamics, ``Rotor.save(path)``, TOML) as a rotorcheck rig.

ROSS writes one top-level table per element, named ``"<ElementClass>_<tag>"`` (``ShaftElement_*``,
``DiskElement_*``, ``BearingElement_*``, ``SealElement_*``, ``PointMass_*``, ...), plus
``ross_version`` and a ``[parameters]`` table. :func:`import_ross` reads such a file and returns the
rig document (a mapping that :func:`rotorcheck.config.parse_config` validates) together with one
sentence for everything that could not be carried over exactly (:class:`RossImport`).

Mapping (ROSS 2.3.0's file format and analysis, ``ross/rotor_assembly.py``, ``shaft_element.py``,
``bearing_seal_element.py``):

* nodes: ROSS node ``k`` (0-based, shaft nodes 0..N, then extra nodes N+1, N+2, ... for pedestals)
  becomes station ``k + 1``; the extra nodes thus become the rig's support nodes after the last
  station. Numbering with gaps is closed up, and the import says so;
* shaft elements: the span of element number ``n`` joins stations ``n + 1`` and ``n + 2``; elements
  with the same ``n`` are concentric layers of that span (the rig takes them as several ``shaft``
  entries on one station pair, whose matrices add, as ROSS's do). Station positions are the running
  sum of the span lengths, as ROSS places its nodes. ``shear_method_calc = "cowper"`` is Cowper's
  formula in both programs; ROSS's ``"hutchinson"`` is not Hutchinson's formula (it lacks a factor
  ``1 + nu``), so such an element gets the coefficient ROSS actually uses as ``shear_coefficient``;
* materials: one rig material per distinct ``(rho, E, G_s)``, named as in ROSS;
* discs (``m``, ``Id``, ``Ip``) and point masses (``mx``, ``my``) carry over as they are;
* bearings and seals: each coefficient is a number, or a ``{speed_rpm, values}`` table sampled
  from the interpolant ROSS builds from the saved lists (a cubic smoothing spline,
  ``scipy.interpolate.UnivariateSpline`` with its default smoothing, for 4 or more speeds; linear or
  quadratic ``interp1d`` for 2 or 3), at ``speed_points`` evenly spaced speeds plus the saved ones.
  ROSS's "frequency" of a bearing coefficient is the rotor speed (rad/s); outside the saved speeds
  ROSS extrapolates, the rig's entry does so linearly (``extrapolate: linear``). Grounded bearings and seals
  on one node are summed into one entry (the rig allows one per station);
* damping: ROSS's rotor-level proportional damping (``parameters.alpha``, ``beta``: M and K of the
  rotor without bearings, discs and point masses included) becomes ``damping: {kind: rayleigh,
  scope: rotor}``; its element damping (``ShaftElement`` ``alpha``, ``beta``, the same on every
  element) becomes ``scope: shaft_elements`` (discs and point masses undamped, as in ROSS).

Axial and torsional terms are dropped: rotorcheck's model is lateral only.

Modules, in the order the import runs: ``tables`` (the bounded TOML load and typed table getters),
``shaft`` (shaft elements, materials, ROSS's shear coefficient), ``layout`` (nodes as stations),
``masses`` (discs and point masses), ``bearings`` (bearings and seals, ROSS's interpolants, the speed
grid), ``parameters`` (speeds and damping), ``importer`` (``import_ross`` and :class:`RossImport`).
"""

from rotorcheck.ross_import.importer import ROSS_FORMAT_VERSION, RossImport, import_ross
from rotorcheck.ross_import.shaft import ross_hutchinson_coefficient
from rotorcheck.ross_import.tables import MAX_ROSS_BYTES

__all__ = ["MAX_ROSS_BYTES", "ROSS_FORMAT_VERSION", "RossImport", "import_ross", "ross_hutchinson_coefficient"]
