"""Each photo's camera pitch, searched by the fit's cost.

A phone held by hand is rarely level: people tilt it a few degrees to frame the person. A
pitch turns the camera about its own centre, which a level camera placed higher or lower
imitates only to first order (both move the person up or down the photo): the pitch also
draws the body's upper half larger or smaller than its lower half, and a level fit of a
pitched photo answers with a body whose legs and trunk are as much too long or short (the
inside leg's error followed the side photo's pitch by r = -0.77 on the standing set,
docs/accuracy.md). Solved as a free parameter with the camera's place, the pitch trades
with the camera's height and lost (docs/history.md); the fit's cost over whole solves
tells it apart.

The search (:func:`searched_pitches`) starts from the fit with the cameras level. For each
view, the local solver is run again from that answer with the view's camera pitched
``PITCH_STEP_DEG`` down and up (the other view's level), ``PITCH_ITERATIONS`` iterations
at most. Each answer is scored by its cost plus ``PITCH_PRIOR`` per squared degree (a
level photo's answer also lowers its cost a little when pitched, the pitch taking up some
of the body's misfit); each view takes the pitch of its best score (level, down or up),
both pitched views are solved together once more, and the answer is the best-scored
solve of them all (four or five solves after the level one). Pinhole views only (an
orthographic view has no camera to turn).

Pitch: degrees, positive looks down (:class:`~bodyfit.fitter.fit.pinhole_canvas.Placement`).
"""

from __future__ import annotations

from typing import Callable, TypeVar

__all__ = ["PITCHES", "PITCH_STEP_DEG", "PITCH_ITERATIONS", "PITCH_VIEWS", "PITCH_PRIOR",
           "searched_pitches", "pitch_text"]

#: How a fit treats the cameras' pitch: ``"searched"`` (:func:`searched_pitches`) or
#: ``"level"`` (both cameras level, the replaced default).
PITCHES = ("searched", "level")
#: How far each view's camera is pitched down and up from level in the search, degrees.
PITCH_STEP_DEG = 4.0
#: The local solver's iterations at most for each pitched solve (it starts near its answer).
PITCH_ITERATIONS = 15
#: The views whose pitch is searched (module docstring).
PITCH_VIEWS = ("front", "side")
#: The score (weighted mm) a pitch must win by per squared degree to be taken: 3.2 at 4
#: degrees (a level photo's answer also lowers its cost a little when pitched).
PITCH_PRIOR = 0.2

Answer = TypeVar("Answer")


def searched_pitches(solve_at: Callable[[dict[str, float], Answer], tuple[float, Answer]],
                     level: tuple[float, Answer], views: tuple[str, ...] = PITCH_VIEWS,
                     prior: float = PITCH_PRIOR) -> tuple[Answer, dict[str, float]]:
    """The answer of the search in the module docstring, and its pitches.

    Args:
        solve_at: (pitches by view name, the answer to start from) -> (cost, answer): the
            fit solved again with the cameras so pitched.
        level: (cost, answer) of the fit with every camera level.
        views: the views whose pitch is searched.
        prior: the score added per squared degree of each view's pitch.

    Returns:
        (the best-scored answer, {view name: its camera's pitch in degrees}).
    """
    def scored(cost: float, pitches: dict[str, float]) -> float:
        return cost + prior * sum(value ** 2 for value in pitches.values())

    level_cost, level_answer = level
    flat = {name: 0.0 for name in views}
    tried = [(level_cost, level_answer, flat)]
    chosen = dict(flat)
    for name in views:
        best = level_cost
        for step in (-PITCH_STEP_DEG, PITCH_STEP_DEG):
            trial = flat | {name: step}
            cost, answer = solve_at(trial, level_answer)
            tried.append((scored(cost, trial), answer, trial))
            if tried[-1][0] < best:
                best, chosen[name] = tried[-1][0], step
    if sum(value != 0 for value in chosen.values()) > 1:  # a combination not solved yet
        cost, answer = solve_at(chosen, level_answer)
        tried.append((scored(cost, chosen), answer, chosen))
    _, answer, pitches = min(tried, key=lambda entry: entry[0])
    return answer, pitches


def pitch_text(pitches: dict[str, float]) -> str:
    """The cameras' pitch in words, for the summary and the report (view name -> degrees,
    positive looking down)."""
    return ", ".join(f"{name} {value:+.1f}" for name, value in pitches.items()) + \
        " degrees (+ looks down)"
