"""The settings of one campaign run (`RunSettings`), the settings a campaign can sweep and the
identification models it can run. Standard library only: the command line imports this
module when it registers its options, before any numerical library is loaded."""

from __future__ import annotations

from dataclasses import dataclass

# Settings a campaign can sweep, with their types.
SWEEPABLE: dict[str, type] = {
    "amplitude": float,   # chirp amplitude [rad]
    "wn": float,          # Butterworth frequency [rad/s]
    "Nd": int,            # decimation factor
    "stencil": int,       # central-difference points: 3 (eq. 22) or 5
    "motor_bits": int,    # motor encoder bits per motor turn (joint side: / gear ratio)
    "link_bits": int,     # link encoder bits per turn
    "noise": float,       # current-loop torque noise, multiple of the default (1.25 % tau_max)
    "duration": float,    # experiment length [s]
    "scatter": float,     # relative std of the axis parameters around the model
}
# Identification model -> the prefix of its table columns.
ID_MODELS = {"joint-motor": "jm", "motor-only": "mo", "motor-only-printed": "mp"}
BIAS_CORRECTABLE = ("joint-motor", "motor-only")


class CampaignError(ValueError):
    """Bad campaign input or a table that does not belong to this campaign (exit status 2)."""


@dataclass(frozen=True)
class RunSettings:
    """What one virtual experiment and its identification use. None: the project default
    (amplitude: the automatic chirp; motor_bits 17, link_bits 20; wn, Nd, stencil: what
    `identify` chooses from the log's first mode, identification.filter_choice.choose_filter).

    Raises CampaignError for an unknown or repeated identification model, a stencil other than
    3 or 5, or a replica count of 1."""

    model: str = "prototype"
    joint: str | None = None
    duration: float = 60.0
    amplitude: float | None = None
    noise: float = 1.0
    motor_bits: int | None = None
    link_bits: int | None = None
    scatter: float = 0.0
    wn: float | None = None
    Nd: int | None = None
    stencil: int | None = None
    effect: str | None = None
    id_models: tuple[str, ...] = ("joint-motor", "motor-only")
    debias: int = 0   # bias-correction replicas per two-mass identification (0: none)
    rate: float | None = None   # acquisition and control rate [Hz] (None: the bench default, PAPER_RATE)

    def __post_init__(self):
        if not self.id_models:
            raise CampaignError("at least one identification model is needed")
        for m in self.id_models:
            if m not in ID_MODELS:
                raise CampaignError(f"unknown identification model {m!r} "
                                    f"(choices: {', '.join(ID_MODELS)})")
        if self.stencil not in (None, 3, 5):
            raise CampaignError(f"stencil must be 3 (eq. 22) or 5 points, got {self.stencil}")
        if self.debias != 0 and self.debias < 2:
            raise CampaignError(f"--debias needs 0 (off) or at least 2 replicas, got "
                                f"{self.debias}")
        if len(set(self.id_models)) != len(self.id_models):
            raise CampaignError(f"identification models repeated: {', '.join(self.id_models)}")


def debiased_models(settings: RunSettings) -> tuple[str, ...]:
    """The identification models whose estimates a run bias-corrects (--debias B > 0)."""
    if not settings.debias:
        return ()
    return tuple(m for m in settings.id_models if m in BIAS_CORRECTABLE)
