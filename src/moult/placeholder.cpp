// placeholder: keeps the moult target buildable until its sources land
