"""The heavy objects of a study run - drivetrains, assembled models, modes - built once, on demand.

A stage asks the context for what it needs; the first ask builds it, later asks (by any stage)
get the same object. Nothing is built for a stage whose stored result still holds, so a warm
re-run loads no model at all. There is one drivetrain per set-up and damping assumption, one
assembled model of it and one modal result per purpose: the modes as ``flexshaft modes`` lists
them, and every mode for the responses (as ``flexshaft frf``/``simulate`` use them).
"""

from __future__ import annotations

from dataclasses import dataclass, field

from .studyfile import Study

__all__ = ["Context"]


@dataclass
class Context:
    """Memoised drivetrains, models and modes of a study's set-ups.

    Parameters
    ----------
    study : Study
    allow_code : bool
        Run part code the model files name beyond flexshaft's own part library.
    use_cache : bool
        Read CAD parts' section tables from the disk cache.
    progress : callable, optional
        ``progress(label)`` -> ``(done, total)`` callback, for slicing CAD parts.
    """

    study: Study
    allow_code: bool = False
    use_cache: bool = True
    progress: object = None
    _memo: dict = field(default_factory=dict)

    def _get(self, key, build):
        if key not in self._memo:
            self._memo[key] = build()
        return self._memo[key]

    def loaded(self, path):
        """A model file as loaded (parts sliced, the section cache used), before any meshing choice."""
        from ..input.modelfile import load_model

        return self._get(
            ("loaded", str(path)),
            lambda: load_model(
                path, progress=self.progress, allow_code=self.allow_code, use_cache=self.use_cache
            ),
        )

    def max_hz(self, setup: str) -> float | None:
        """The set-up's range of interest, Hz: the study's, else its model file's ``[model] max_hz``."""
        if self.study.max_hz is not None:
            return self.study.max_hz
        return self.loaded(self.study.setup(setup).model).max_hz

    def mesh_choice(self, setup: str):
        """The set-up's drivetrain meshed for its range of interest (:func:`mesh_for_range`)."""

        def build():
            from ..analysis.convergence import mesh_for_range

            d = self.loaded(self.study.setup(setup).model)
            return mesh_for_range(d, self.max_hz(setup))

        return self._get(("mesh", setup), build)

    def drivetrain(self, setup: str, variant: str = "parts"):
        """The set-up's drivetrain under a damping assumption (``"parts"`` or ``"system"``)."""

        def build():
            d = self.mesh_choice(setup).drivetrain
            if variant == "system":
                from ..analysis.systemdamping import system_damped

                d = system_damped(d, self.study.system_damping_ratio)
            return d

        return self._get(("drivetrain", setup, variant), build)

    def model(self, setup: str, variant: str = "parts"):
        """The one assembled model of a set-up under a damping assumption."""
        from ..model.assembly import assemble

        return self._get(("model", setup, variant), lambda: assemble(self.drivetrain(setup, variant)))

    def modes(self, setup: str, variant: str = "parts"):
        """The modes as ``flexshaft modes`` lists them: the study's count, else up to max_hz, else 20."""
        from ..analysis.modal import listing_modes

        count, top = self.study.modes.count, self.max_hz(setup)
        return self._get(
            ("modes", setup, variant), lambda: listing_modes(self.model(setup, variant), count, top)
        )

    def response_modes(self, setup: str, variant: str = "parts"):
        """Every mode (up to the dense limit) for the responses, as ``flexshaft frf``/``simulate`` use."""
        from ..analysis.modal import response_modes

        return self._get(("all", setup, variant), lambda: response_modes(self.model(setup, variant)))
