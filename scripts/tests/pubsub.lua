-- Messages between scenes and tools: troupe.publish / troupe.subscribe (docs/lua-api.md).

test("a published message arrives at the start of the next tick, as a table", function()
  local got = {}
  troupe.subscribe("cue/*", function(value, key)
    got[#got + 1] = { tick = troupe.tick(), key = key, value = value }
  end)
  local sent_at = troupe.tick()
  troupe.publish("cue/start", { actor = "ann", at = { 1, 2.5, -3 }, loud = true })
  expect(#got == 0, "not delivered in the tick it was published")
  run(0.01)
  expect(#got == 1, "delivered once, got " .. #got)
  expect(got[1].key == "cue/start", "the key is passed along")
  expect(got[1].value.actor == "ann" and got[1].value.loud == true, "fields kept")
  expect(got[1].value.at[2] == 2.5 and got[1].value.at[3] == -3, "arrays kept")
  expect(got[1].tick == sent_at + 1, "seen in the script phase of the next tick")
end)

test("subscribers see messages in publishing order, each in subscription order", function()
  local log = {}
  troupe.subscribe("a/**", function(v, key) log[#log + 1] = "first " .. key .. "=" .. tostring(v) end)
  troupe.subscribe("a/x", function(v, key) log[#log + 1] = "second " .. key .. "=" .. tostring(v) end)
  troupe.publish("a/x", 1)
  troupe.publish("a/y/z", "two")
  troupe.publish("b/x", 3)
  run(0.01)
  local want = { "first a/x=1", "second a/x=1", "first a/y/z=two" }
  expect(#log == #want, "three deliveries, got " .. #log)
  for i, line in ipairs(want) do expect(log[i] == line, "got " .. tostring(log[i])) end
end)

test("a behavior can publish and another can wait for it", function()
  local ann = troupe.actor{ name = "ann" }
  local bob = troupe.actor{ name = "bob" }
  local heard = nil
  troupe.subscribe("greet", function(v) heard = v.from end)
  ann:behave(function() wait(0.2); troupe.publish("greet", { from = "ann" }) end)
  bob:behave(function() wait_until(function() return heard ~= nil end, 1) end)
  run(0.5)
  expect(heard == "ann", "bob heard ann")
  expect(bob:behavior_status() == "done", "bob's wait ended")
end)

test("lists, records, nesting and empty tables arrive as they were published", function()
  local got = nil
  troupe.subscribe("shape", function(v) got = v end)
  local deep = { "bottom" }   -- with the message itself, 100 tables deep
  for _ = 1, 98 do deep = { deep } end
  troupe.publish("shape", { list = { 1, 2, 3 }, record = { a = 1, b = "two" }, empty = {}, deep = deep,
                            flag = false })
  run(0.02)
  expect(got ~= nil and #got.list == 3 and got.list[3] == 3 and got.record.b == "two", "list and record")
  expect(next(got.empty) == nil and got.flag == false, "empty table, false")
  local d = got.deep
  for _ = 1, 98 do d = d[1] end
  expect(d[1] == "bottom", "100 tables deep")
end)

test("bad keys and values are refused with a message", function()
  local function refusal(f, ...)
    local ok, err = pcall(f, ...)
    expect(not ok, "refused")
    return tostring(err)
  end
  local err = refusal(troupe.publish, "cue/*", 1)
  expect(err:find("without '%*'"), err)
  err = refusal(troupe.publish, "cue", function() end)
  expect(err:find("publish cue"), err)
  err = refusal(troupe.subscribe, "cue//x", function() end)
  expect(err:find("subscribe"), err)
  -- JSON has no NaN nor infinity: said, with where, rather than sent as null.
  err = refusal(troupe.publish, "cue/nan", 0/0)
  expect(err:find("publish cue/nan: value is not a finite number", 1, true), err)
  err = refusal(troupe.publish, "cue/t", { x = 1, y = { 2, 1/0 } })
  expect(err:find("value.y[2] is not a finite number", 1, true), err)
  -- One table held twice at every level: looked into once (2^64 visits before).
  local shared = {}
  shared[1], shared[2] = shared, shared
  err = refusal(troupe.publish, "cue/shared", shared)
  expect(err:find("publish cue/shared", 1, true), err)
  -- A list is keys 1…n, a record string keys: other tables would lose keys as JSON.
  err = refusal(troupe.publish, "cue/mixed", { 1, 2, a = 3 })
  expect(err:find("publish cue/mixed: value is neither a list nor a record (string keys): it has both list keys", 1, true), err)
  err = refusal(troupe.publish, "cue/sparse", { x = { [1] = 1, [3] = 3 } })
  expect(err:find("value.x is neither a list nor a record (string keys): it has [3] among 2 keys (a list's are 1…2)", 1, true), err)
  err = refusal(troupe.publish, "cue/far", { [10] = "x" })
  expect(err:find("it has [10] among 1 keys", 1, true), err)
  err = refusal(troupe.publish, "cue/half", { [1.5] = "x" })
  expect(err:find("it has [1.5]", 1, true), err)
  -- Deep nesting is refused (it crashed the process 20,000 deep); a DAG of doubling
  -- tables would be 2^60 parts written out.
  local deep = {}
  for _ = 1, 20000 do deep = { deep } end
  err = refusal(troupe.publish, "cue/deep", deep)
  expect(err:find("publish cue/deep: value[1][1][1][1]…(92 more)…[1][1][1][1] nests tables more than 100 deep", 1, true), err)
  local dag = { 1 }
  for _ = 1, 60 do dag = { dag, dag } end
  err = refusal(troupe.publish, "cue/dag", dag)
  expect(err:find("publish cue/dag: the value has more than 1000000 parts", 1, true), err)
  err = refusal(troupe.subscribe, "cue/x", 5)
  expect(err:find("subscribe: argument 2 must be a function(value, key), got integer", 1, true), err)
  err = refusal(troupe.publish, 5, 1)
  expect(err:find("publish: argument 1 (the key) must be a string, got integer", 1, true), err)
end)
