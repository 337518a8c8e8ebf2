-- expect: line 4: object 'j': a joint needs 'body_a', the body it holds
-- A raw joint that holds nothing.

object { name = "j", joint = "hinge", anchor = { 0, 0 } }
