-- The plaza of scripts/tests/plaza.lua on twelve layouts, to measure a change that moves
-- its walkers (docs/navigation.md, "Measuring a change on twelve layouts"). The scene is
-- chaotic: one layout's worst contact moves by centimetres either way with any change,
-- so a change is judged on the twelve together. Each layout is one test printing one
-- line: who arrived and when, the deepest interpenetration of solids (and between what),
-- of body discs, the mean detour, the lowest pelvis, and the contacts of solids deeper
-- than 1 cm sampled every fifth tick, grouped into events (one pair's run of such
-- samples) by kind, with each kind's deepest; then each walker that has not arrived,
-- where it stands, since when, and who is nearest. It checks nothing. Two at a time in a
-- release build (about 35 s a layout on this kind of machine):
--   troupe test scripts/tests/support/plaza_layouts.lua --shard 1/2 &
--   troupe test scripts/tests/support/plaza_layouts.lua --shard 2/2
local plaza = require("plaza_streams")

-- Seconds the walkers have, as in plaza.lua.
local TIME_BOUND = 150
-- Contacts deeper than this (m) are counted.
local CONTACT = 0.01
-- Whether to print each event as it begins too: when, what, and whether the walker is
-- within 1 m of a planter.
local EACH_EVENT = false
-- The layouts: how far the streams start (`back`) and how far apart their goals spread
-- (`spread`), the test's first (see plaza_streams.lua).
local LAYOUTS = {
  { 11, 1.5 }, { 11.5, 1.4 }, { 10.5, 1.6 }, { 11.2, 1.5 }, { 10.8, 1.45 }, { 11, 1.55 },
  { 11.3, 1.45 }, { 10.7, 1.55 }, { 11.4, 1.6 }, { 10.6, 1.45 }, { 11.1, 1.42 }, { 10.9, 1.58 },
}

-- The kind of body part a solid's name is (a foot, a leg, a hand, …).
local function part(solid)
  if not solid then return "planter" end
  for _, p in ipairs({ "foot", "toe", "thigh", "leg", "hand", "arm", "pelvis", "head" }) do
    if solid:find(p) then return p end
  end
  return solid
end

-- The kind of a contact: its two parts, in alphabetical order ("foot-planter",
-- "foot-leg").
local function kind(solid, other_solid)
  local a, b = part(solid), part(other_solid)
  if other_solid and a > b then a, b = b, a end
  return a .. "-" .. b
end

for _, layout in ipairs(LAYOUTS) do
  local back, spread = layout[1], layout[2]
  test(string.format("the plaza with back %.2f m, spread %.2f m", back, spread), function()
    local o = {}
    for k, v in pairs(plaza.BUSY) do o[k] = v end
    o.back, o.spread = back, spread
    local actors, walks, walked, straight, last, goals = {}, {}, {}, {}, {}, {}
    -- Since when each walker has stood (moving no faster than 0.1 m/s); nil while it moves.
    local still_since = {}
    for i, w in ipairs(plaza.build(o)) do
      actors[i] = w.actor
      goals[i] = { w.gx, w.gz }
      walks[i] = w.actor:walk{ to = { w.gx, 0, w.gz }, speed = 1.3 }
      straight[i] = math.sqrt((w.gx - w.x)^2 + (w.gz - w.z)^2)
      walked[i] = 0
      last[i] = w.actor:position()
    end
    local tick, contacts, run = 0, 0, nil
    local solids, discs, lowest = { 0, "nothing" }, 0, math.huge
    local events, deepest_of = {}, {}
    run_until(function()
      tick = tick + 1
      for i, a in ipairs(actors) do
        local p = a:position()
        local step = math.sqrt((p[1] - last[i][1])^2 + (p[3] - last[i][3])^2)
        walked[i] = walked[i] + step
        last[i] = p
        if step > 0.1 / troupe.rate() then
          still_since[i] = nil
        elseif not still_since[i] then
          still_since[i] = troupe.time()
        end
      end
      if tick % 5 == 0 then
        local d, a, b, sa, sb = troupe.deepest_overlap()
        if d > solids[1] then
          solids = { d, string.format("%s's %s and %s%s at %.1f s", a, sa, b,
                                      sb and ("'s " .. sb) or "", troupe.time()) }
        end
        if d > CONTACT then
          contacts = contacts + 1
          local pair = a .. (sa or "") .. b .. (sb or "")
          local k = kind(sa, sb)
          if pair ~= run then
            events[k] = (events[k] or 0) + 1
            if EACH_EVENT then
              local p = troupe.get_actor(a):position()
              local reach = plaza.BUSY.planter_size[1] / 2 + 1
              local near = math.abs(math.abs(p[1]) - o.planter) < reach
                and math.abs(math.abs(p[3]) - o.planter) < reach
              print(string.format("  event at %.2f s: %s's %s and %s%s, %.3f m, %s", troupe.time(), a, sa, b,
                                  sb and ("'s " .. sb) or "", d, near and "by a planter" or "in the open"))
            end
          end
          deepest_of[k] = math.max(deepest_of[k] or 0, d)
          run = pair
        else
          run = nil
        end
        discs = math.max(discs, (troupe.deepest_overlap{ discs = true }))
        for _, actor in ipairs(actors) do lowest = math.min(lowest, actor:position()[2]) end
      end
      return plaza.ended(walks)
    end, TIME_BOUND)
    local arrived, detour = plaza.tally(walks, walked, straight)
    -- Who has not arrived: where, since when it stands, and who is nearest.
    for i, a in ipairs(actors) do
      if walks[i].status ~= "completed" then
        local p = a:position()
        local nearest, gap = nil, math.huge
        for j, b in ipairs(actors) do
          local q = b:position()
          local d = math.sqrt((p[1] - q[1])^2 + (p[3] - q[3])^2)
          if j ~= i and d < gap then nearest, gap = j, d end
        end
        print(string.format("  %s (%s) at (%.2f, %.2f), %.2f m from its goal (%.2f, %.2f), standing since %.1f s; nearest %s, %.2f m, %s",
          a.name, walks[i].status, p[1], p[3], math.sqrt((p[1] - goals[i][1])^2 + (p[3] - goals[i][2])^2),
          goals[i][1], goals[i][2], still_since[i] or troupe.time(), actors[nearest].name, gap,
          walks[nearest].status == "completed" and "arrived" or "walking"))
      end
    end
    local kinds = {}
    for k, n in pairs(events) do kinds[#kinds + 1] = string.format("%s %d (%.3f)", k, n, deepest_of[k]) end
    table.sort(kinds)
    print(string.format("layout %.2f/%.2f: %d of %d arrived by %.1f s; deepest solids %.3f m (%s), discs %.3f m; mean detour %.1f %%; lowest pelvis %.3f m; %d contacts over %.0f cm; events: %s",
      back, spread, arrived, #actors, troupe.time(), solids[1], solids[2], discs, 100 * detour,
      lowest, contacts, 100 * CONTACT, #kinds > 0 and table.concat(kinds, ", ") or "none"))
  end, { timeout = TIME_BOUND + 10 })
end
