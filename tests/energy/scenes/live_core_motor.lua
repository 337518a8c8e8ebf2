-- Session 20's two-phase motor with the kit's live iron cores
-- (docs/motor.md "Session 20: live cores"), the sliders let go as in
-- motor_study: the spokes magnetise the four cores as they pass, and each
-- core's moment links the neighbouring coils. Its coupling's books close
-- only if the EMF carries that moment's change (session 21,
-- tests/energy/energy_books_test.cpp ALiveCoreMotorsBooksCloseAsTheStepShrinks;
-- docs/magnetism.md "Induction through soft iron").
world { dt = 1 / 240, seconds = 10, settings = { ["gravity.uniform"] = { g = { 0, -9.81, 0 } },
        rigid_body = { solver = "step" }, electricity = { induction_order = 2 } } }
local m = require "motor.layout" { live_cores = true }
for _, s in ipairs(m.sliders) do at(m.slider_release, s, { pinned = false }) end
