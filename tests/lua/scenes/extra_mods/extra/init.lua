return { height = 3 }
