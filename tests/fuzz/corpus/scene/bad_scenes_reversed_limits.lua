-- expect: line 5: object 'pivot': 'limit_low' (1) is above 'limit_high' (-1)
object { name = "arm", position = { 0.5, 2 }, shape = "box", size = { 1, 0.05, 0.05 }, mass = 1 }

-- Raw joint properties bypass the kit's range check; the loader still refuses them.
object { name = "pivot", joint = "hinge", body_a = "arm", anchor = { 0, 2 }, limit_low = 1, limit_high = -1 }
