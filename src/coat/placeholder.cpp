// placeholder: replaced as the module is implemented
