local kit = require "kit"
return {}
